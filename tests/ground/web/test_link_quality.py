"""LinkQuality: the share of packets received, from MAVLink sequence numbers."""

from __future__ import annotations

import pytest

from ground.web.link_quality import LinkQuality


def test_unknown_before_any_packet_and_whole_without_gaps() -> None:
    quality = LinkQuality()
    assert quality.received_share(1) is None
    for seq in range(250, 260):  # across the wrap at 256
        quality.packet(1, 1, seq % 256)
    assert quality.received_share(1) == 1.0


def test_gaps_count_as_losses_per_component_over_a_window() -> None:
    quality = LinkQuality(window=100)
    for seq in range(0, 40, 2):  # every other packet lost: 20 received, 19 lost
        quality.packet(1, 1, seq)
    quality.packet(1, 191, 7)  # another component has its own counter: no loss
    assert quality.received_share(1) == pytest.approx(21 / 40)
    for seq in range(40, 140):  # then 100 in a row: the window forgets the losses
        quality.packet(1, 1, seq)
    assert quality.received_share(1) == pytest.approx(1.0, abs=0.02)
    assert quality.received_share(2) is None


def test_a_restart_or_reordering_is_not_a_loss() -> None:
    quality = LinkQuality()
    for seq in (10, 11, 12, 0, 1, 200, 201):  # back to 0; then a jump of 199 (> 128)
        quality.packet(3, 1, seq)
    assert quality.received_share(3) == 1.0
