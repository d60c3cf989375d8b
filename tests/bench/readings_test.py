"""bench/wp/readings.py: the two readings of "time to reach error <= e" on hand-made sweeps
whose answers are worked out by hand in each case."""
import os
import sys
import unittest

sys.path.insert(0, os.environ.get("KANESIM_BENCH_WP", os.path.join(os.path.dirname(__file__), "..", "..", "bench", "wp")))
import readings  # noqa: E402


def pts(*rows):
    """(param, error, time) rows; a None error is a failed run."""
    return [dict(param=p, ok=e is not None, error=e, time=t) if e is not None else dict(param=p, ok=False)
            for p, e, t in rows]


class Readings(unittest.TestCase):
    def test_monotone_sweep_reads_the_same_both_ways(self):
        s = pts((1e-3, 1e-2, 1.0), (1e-4, 1e-3, 2.0), (1e-5, 1e-4, 3.0), (1e-6, 1e-5, 4.0))
        for reading in readings.READINGS:
            self.assertEqual(readings.time_to(s, 1e-3, reading), 2.0)
            self.assertEqual(readings.time_to(s, 1e-4, reading), 3.0)
            self.assertIsNone(readings.time_to(s, 1e-6, reading))

    def test_a_lucky_loose_point_counts_for_first_reach_only(self):
        # 1e-4 lands at 5e-4 by luck; 1e-5 is above 1e-3 again; from 1e-6 on it stays below.
        s = pts((1e-3, 2e-2, 1.0), (1e-4, 5e-4, 2.0), (1e-5, 3e-3, 3.0), (1e-6, 8e-4, 4.0), (1e-7, 1e-4, 5.0))
        self.assertEqual(readings.time_to(s, 1e-3, "first"), 2.0)
        self.assertEqual(readings.time_to(s, 1e-3, "stays"), 4.0)
        self.assertEqual(readings.point_at(s, 1e-3, "stays")["param"], 1e-6)

    def test_stays_below_takes_the_cheapest_of_the_tight_end(self):
        # The tight end (1e-6, 1e-7) stays below; the tighter point ran faster (noise).
        s = pts((1e-5, 2e-3, 1.0), (1e-6, 5e-4, 3.0), (1e-7, 1e-4, 2.5))
        self.assertEqual(readings.time_to(s, 1e-3, "stays"), 2.5)

    def test_last_point_above_means_no_stays_below(self):
        s = pts((1e-3, 5e-4, 1.0), (1e-4, 2e-3, 2.0))
        self.assertEqual(readings.time_to(s, 1e-3, "first"), 1.0)
        self.assertIsNone(readings.time_to(s, 1e-3, "stays"))

    def test_failed_runs_are_ignored(self):
        s = pts((1e-3, 2e-3, 1.0), (1e-4, 5e-4, 2.0), (1e-5, None, 0.0))
        for reading in readings.READINGS:
            self.assertEqual(readings.time_to(s, 1e-3, reading), 2.0)

    def test_best_of_separates_kanesim_peers_and_baselines(self):
        tools = {"kanesim a": pts((1e-4, 1e-4, 3.0)), "kanesim b": pts((1e-4, 1e-4, 2.0)),
                 "pinocchio": pts((1e-4, 1e-4, 5.0)), "baseline: minimal ODE": pts((1e-4, 1e-4, 0.1)),
                 "mujoco RK4": pts((1e-3, 1e-2, 0.2))}
        t, tool, pt = readings.best_of(tools, 1e-3, "first", True)
        self.assertEqual((t, tool, pt["param"]), (2.0, "kanesim b", 1e-4))
        t, tool, _ = readings.best_of(tools, 1e-3, "first", False)
        self.assertEqual((t, tool), (5.0, "pinocchio"))  # the baseline is never a peer
        self.assertEqual(readings.best_of(tools, 1e-9, "stays", False), (None, None, None))

    def test_retimed_ratio_is_the_ratio_of_medians_without_failed_runs(self):
        # kanesim 1, 7, 2 (the failed run left out): median 2; peer 4, 100, 6, 5: median
        # (5 + 6) / 2 = 5.5, the outlier 100 without weight.
        rec = dict(kanesim_times=[1.0, None, 7.0, 2.0], peer_times=[4.0, 100.0, 6.0, 5.0])
        self.assertAlmostEqual(readings.retimed_ratio(rec), 2.0 / 5.5)
        self.assertIsNone(readings.retimed_ratio(dict(kanesim_times=[None], peer_times=[1.0])))


if __name__ == "__main__":
    unittest.main()
