"""Tests of robot/estimator.py: the Kalman filter over (s, y, theta)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import EstimatorConfig
from robot.estimator import Estimator, EstimatorLost
from shared.clock import ManualClock, ns_from_s

FRAME_NS = 66_666_667  # 15 frames/s
CONFIG = EstimatorConfig()


def arc_step(pose: tuple[float, float, float], ds: float, dpsi: float) -> tuple[float, ...]:
    """Exact motion along an arc of length ds turning by dpsi (independent of the filter)."""
    s, y, theta = pose
    if abs(dpsi) < 1e-12:
        return s + ds * math.cos(theta), y + ds * math.sin(theta), theta
    radius = ds / dpsi
    return (s + radius * (math.sin(theta + dpsi) - math.sin(theta)),
            y - radius * (math.cos(theta + dpsi) - math.cos(theta)), theta + dpsi)


def started(clock: ManualClock, pose: tuple[float, float, float] = (-1.0, 0.1, 0.05),
            config: EstimatorConfig = CONFIG) -> Estimator:
    estimator = Estimator(config, clock.now_ns())
    assert estimator.update(clock.now_ns(), *pose).outcome == "initialized"
    return estimator


class TestPredict:
    def test_nothing_before_the_first_estimate(self, manual_clock: ManualClock) -> None:
        estimator = Estimator(CONFIG, manual_clock.now_ns())
        estimator.predict(0.5, 0.1)
        assert estimator.estimate is None

    def test_coasting_follows_the_odometry(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        truth = (-1.0, 0.1, 0.05)
        variances = []
        for k in range(45):  # 3 s at 15 Hz, turning left then right
            ds, dpsi = 0.2 / 15, 0.01 * math.sin(k / 7)
            estimator.predict(ds, dpsi)
            truth = arc_step(truth, ds, dpsi)
            variances.append(estimator.estimate.covariance[1, 1])
        estimate = estimator.estimate
        assert (estimate.s_m, estimate.y_m, estimate.theta_rad) == pytest.approx(truth, abs=1e-12)
        assert np.all(np.diff(variances) > 0)  # uncertainty grows while coasting

    def test_known_step(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock, (0.0, 0.0, 0.0))
        estimator.predict(math.pi / 2, math.pi / 2)  # a quarter circle of radius 1 m
        estimate = estimator.estimate
        assert (estimate.s_m, estimate.y_m, estimate.theta_rad) == pytest.approx(
            (1.0, 1.0, math.pi / 2))

    def test_heading_stays_wrapped(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock, (0.0, 0.0, math.pi - 0.01))
        estimator.predict(0.0, 0.02)
        assert estimator.estimate.theta_rad == pytest.approx(-math.pi + 0.01)

    def test_non_finite_odometry(self, manual_clock: ManualClock) -> None:
        with pytest.raises(ValueError, match="ds_m must be finite"):
            started(manual_clock).predict(math.nan, 0.0)


class TestUpdate:
    def test_converges_to_the_truth_under_noise(
        self, manual_clock: ManualClock, rng: np.random.Generator
    ) -> None:
        sigma = np.array([CONFIG.sigma_s_m, CONFIG.sigma_y_m, CONFIG.sigma_theta_rad])
        truth = (-3.0, 0.25, -0.1)
        estimator = started(manual_clock, tuple(np.array(truth) + sigma * rng.normal(size=3)))
        raw_errors, filtered_errors = [], []
        for k in range(300):  # 20 s at 0.2 m/s, weaving
            ds, dpsi = 0.2 / 15, 0.012 * math.sin(k / 20)
            truth = arc_step(truth, ds, dpsi)
            # odometry with the simulator's kind of errors: scale and white noise
            estimator.predict(ds * 1.01 + rng.normal(0, 5e-4), dpsi * 1.03 + rng.normal(0, 5e-4))
            manual_clock.advance_ns(FRAME_NS)
            measured = np.array(truth) + sigma * rng.normal(size=3)
            assert estimator.update(manual_clock.now_ns(), *measured).used
            if k >= 60:
                raw_errors.append(measured[1] - truth[1])
                filtered_errors.append(estimator.estimate.y_m - truth[1])
        raw_rms = math.sqrt(np.mean(np.square(raw_errors)))
        filtered_rms = math.sqrt(np.mean(np.square(filtered_errors)))
        assert raw_rms == pytest.approx(CONFIG.sigma_y_m, rel=0.2)
        assert filtered_rms < 0.5 * raw_rms
        estimate = estimator.estimate
        error = np.array([estimate.s_m, estimate.y_m, estimate.theta_rad]) - truth
        assert error @ np.linalg.solve(estimate.covariance, error) < 16.3  # chi2(3), p = 0.999

    def test_gate_rejects_an_outlier(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        manual_clock.advance_ns(FRAME_NS)
        result = estimator.update(manual_clock.now_ns(), -1.0, 1.1, 0.05)
        assert result.outcome == "rejected" and not result.used
        assert result.mahalanobis2 > CONFIG.gate_chi2
        assert estimator.estimate.y_m == pytest.approx(0.1)

    def test_no_gate_accepts_everything(self, manual_clock: ManualClock) -> None:
        config = EstimatorConfig(gate_chi2=None)
        estimator = started(manual_clock, config=config)
        assert estimator.update(manual_clock.now_ns(), -1.0, 1.1, 0.05).outcome == "accepted"

    def test_heading_compared_on_the_circle(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock, (0.0, 0.0, math.pi - 0.01))
        result = estimator.update(manual_clock.now_ns(), 0.0, 0.0, -math.pi + 0.01)
        assert result.outcome == "accepted"
        assert abs(estimator.estimate.theta_rad) == pytest.approx(math.pi, abs=1e-9)

    def test_time_must_not_go_backwards(self, manual_clock: ManualClock) -> None:
        manual_clock.advance_ns(10)
        estimator = started(manual_clock)
        with pytest.raises(ValueError, match="went backwards"):
            estimator.update(5, 0.0, 0.0, 0.0)

    def test_non_finite_estimate(self, manual_clock: ManualClock) -> None:
        with pytest.raises(ValueError, match="y_m must be finite"):
            Estimator(CONFIG, 0).update(0, 0.0, math.inf, 0.0)


class TestPoll:
    def test_lost_at_the_timeout_not_before(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        for _ in range(29):  # coasting through frames without an estimate
            manual_clock.advance_ns(FRAME_NS)
            estimator.predict(0.2 / 15, 0.0)
            assert estimator.poll(manual_clock.now_ns()) is None
        manual_clock.sleep_until_ns(CONFIG.lost_timeout_ns - 1)
        assert estimator.poll(manual_clock.now_ns()) is None
        assert not estimator.lost
        manual_clock.advance_ns(1)
        event = estimator.poll(manual_clock.now_ns())
        assert event == EstimatorLost(t_ns=CONFIG.lost_timeout_ns, reason="no_estimate",
                                      since_update_ns=CONFIG.lost_timeout_ns,
                                      limit_ns=CONFIG.lost_timeout_ns, rejected=0,
                                      driven_m=pytest.approx(29 * 0.2 / 15),
                                      limit_m=CONFIG.lost_distance_m)
        assert event.message == "no usable vision estimate for 2.00 s (limit 2.00 s)"
        assert estimator.lost
        manual_clock.advance(1.0)
        assert estimator.poll(manual_clock.now_ns()) is None  # declared once

    def test_lost_after_the_distance_on_odometry_alone_at_any_speed(
            self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        for _ in range(7):  # 0.125 m a frame: 1.9 m/s, far inside the timeout
            manual_clock.advance_ns(FRAME_NS)
            estimator.predict(0.125, 0.0)
            assert estimator.poll(manual_clock.now_ns()) is None
        manual_clock.advance_ns(FRAME_NS)
        estimator.predict(0.125, 0.0)
        event = estimator.poll(manual_clock.now_ns())
        assert event is not None and event.driven_m == pytest.approx(1.0)
        assert event.message == "no usable vision estimate for 1.00 m driven (limit 1.00 m)"

    def test_an_accepted_estimate_restarts_the_distance(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        estimator.predict(0.9, 0.0)
        moved = estimator.estimate
        assert estimator.update(manual_clock.now_ns(), moved.s_m, moved.y_m,
                                moved.theta_rad).outcome == "accepted"
        estimator.predict(0.9, 0.0)
        assert estimator.poll(manual_clock.now_ns()) is None

    def test_time_stood_still_for_the_safety_layer_does_not_count(
            self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        manual_clock.advance(1.5)
        estimator.stood_still(ns_from_s(30.0))  # waited for a person to pass
        manual_clock.advance(30.4)
        assert estimator.poll(manual_clock.now_ns()) is None
        manual_clock.advance(0.1)
        assert estimator.poll(manual_clock.now_ns()) is not None

    def test_counts_from_construction_without_any_estimate(self) -> None:
        estimator = Estimator(CONFIG, ns_from_s(100.0))
        assert estimator.poll(ns_from_s(101.9)) is None
        assert estimator.poll(ns_from_s(102.0)) is not None

    def test_rejected_estimates_do_not_keep_it_alive(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        for _ in range(31):
            manual_clock.advance_ns(FRAME_NS)
            estimator.update(manual_clock.now_ns(), -1.0, 2.0, 0.05)
        event = estimator.poll(manual_clock.now_ns())
        assert event is not None and event.reason == "rejected" and event.rejected == 31
        assert event.message.startswith("31 estimates rejected by the gate for 2.07 s")

    def test_an_accepted_estimate_restarts_the_timer(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        manual_clock.advance(1.5)
        estimator.update(manual_clock.now_ns(), -1.0, 0.1, 0.05)
        manual_clock.advance(1.5)
        assert estimator.poll(manual_clock.now_ns()) is None

    def test_first_estimate_after_lost_reinitializes(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        manual_clock.advance(3.0)
        assert estimator.poll(manual_clock.now_ns()) is not None
        result = estimator.update(manual_clock.now_ns(), 0.5, -0.4, 0.3)  # far, but no gate
        assert result.outcome == "initialized"
        assert not estimator.lost
        assert estimator.estimate.y_m == -0.4


class TestSwitchSegment:
    def test_moves_mean_and_covariance(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock, (-0.1, 0.05, 0.02))
        estimator.switch_segment((1.0, 0.0, math.pi / 2))
        estimate = estimator.estimate
        # the robot is 1.1 m behind and 0.05 m left of a key image turned 90 degrees left
        assert (estimate.s_m, estimate.y_m, estimate.theta_rad) == pytest.approx(
            (0.05, 1.1, 0.02 - math.pi / 2))
        # s and y swap their roles, so their variances swap
        assert estimate.covariance[0, 0] == pytest.approx(CONFIG.sigma_y_m**2)
        assert estimate.covariance[1, 1] == pytest.approx(CONFIG.sigma_s_m**2)

    def test_nothing_before_the_first_estimate(self) -> None:
        estimator = Estimator(CONFIG, 0)
        estimator.switch_segment((0.5, 0.0, 0.0))
        assert estimator.estimate is None


class TestReset:
    def test_forgets_the_state_and_restarts_the_timer(self, manual_clock: ManualClock) -> None:
        estimator = started(manual_clock)
        manual_clock.advance(3.0)
        assert estimator.poll(manual_clock.now_ns()) is not None
        estimator.reset(manual_clock.now_ns())
        assert estimator.estimate is None and not estimator.lost
        manual_clock.advance(1.9)
        assert estimator.poll(manual_clock.now_ns()) is None


def test_tracking_from_the_first_update_until_lost_or_reset() -> None:
    estimator = Estimator(EstimatorConfig(lost_timeout_ns=ns_from_s(1.0)), 0)
    assert not estimator.tracking
    estimator.update(ns_from_s(0.1), -0.3, 0.02, 0.01)
    assert estimator.tracking
    assert estimator.poll(ns_from_s(2.0)) is not None and not estimator.tracking
    estimator.update(ns_from_s(2.1), -0.3, 0.02, 0.01)
    assert estimator.tracking
    estimator.reset(ns_from_s(2.2))
    assert not estimator.tracking
