"""STATUSTEXT (253): human-readable notices to the ground station, chunked when long.

``text`` holds 50 bytes. A longer notice goes out as chunks sharing a non-zero
``id`` with ``chunk_seq`` 0, 1, ...; the last chunk is shorter than 50 bytes
(an empty one follows a full last chunk), which is how receivers know the text
ended (common.xml STATUSTEXT). MAVProxy prints them as ``AP: ...``.
"""

from __future__ import annotations

from shared.mavlink.dialect import Message, mavlink

#: Bytes in one STATUSTEXT's ``text`` field.
TEXT_LEN = 50


def statustext_messages(severity: int, text: str, chunk_id: int = 1) -> list[Message]:
    """The STATUSTEXT messages carrying ``text``.

    Args:
        severity: a ``MAV_SEVERITY`` (e.g. ``MAV_SEVERITY_WARNING``).
        text: the notice; non-ASCII characters become ``?``.
        chunk_id: 1-65535, shared by the chunks of a long notice; the caller varies it
            between notices so chunks of two notices never mix. Unused (0 on the
            wire) when the text fits one message.
    """
    data = text.encode("ascii", errors="replace")
    if len(data) <= TEXT_LEN:
        return [mavlink.MAVLink_statustext_message(severity, data)]
    if not 1 <= chunk_id <= 0xFFFF:
        raise ValueError(f"chunk_id must be in 1..65535, got {chunk_id}")
    chunks = [data[i:i + TEXT_LEN] for i in range(0, len(data), TEXT_LEN)]
    if len(chunks[-1]) == TEXT_LEN:
        chunks.append(b"")
    return [mavlink.MAVLink_statustext_message(severity, chunk, id=chunk_id, chunk_seq=seq)
            for seq, chunk in enumerate(chunks)]
