"""STATUSTEXT: one message up to 50 bytes, chunks beyond."""

from __future__ import annotations

from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.statustext import TEXT_LEN, statustext_messages

WARNING = mavlink.MAV_SEVERITY_WARNING


def decoded(text: str, chunk_id: int = 9) -> list[mavlink.MAVLink_statustext_message]:
    vehicle, ground = make_codec(1, 1), make_codec(255, 190)
    return [m for msg in statustext_messages(WARNING, text, chunk_id)
            for m in ground.parse(vehicle.pack(msg))]


def test_short_text_is_one_message() -> None:
    (msg,) = decoded("mission refused: item 1: no key image 500")
    assert (msg.text, msg.severity, msg.id, msg.chunk_seq) == (
        "mission refused: item 1: no key image 500", WARNING, 0, 0)


def test_long_text_is_chunked_under_one_id() -> None:
    text = "x" * 60 + "é"
    msgs = decoded(text)
    assert [(m.id, m.chunk_seq) for m in msgs] == [(9, 0), (9, 1)]
    assert "".join(m.text for m in msgs) == "x" * 60 + "?"


def test_full_last_chunk_is_followed_by_an_empty_one() -> None:
    msgs = decoded("y" * (2 * TEXT_LEN))
    assert [len(m.text) for m in msgs] == [50, 50, 0]
