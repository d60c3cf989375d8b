"""The two readings of "the time a tool needs to reach error <= e" from one sweep (a list of
points dict(param, ok, time, error), param a tolerance or a fixed step: smaller is tighter).

first reach  the cheapest point whose error is <= e. On a chaotic horizon the error of a
             point scatters by up to ~10x around the trend (where the step sequence lands
             decides it), so a loose point can land below e by luck; the reading then
             rewards the luckier sweep.
stays below  the cheapest point among those from which on, tightening further, every
             measured point's error is <= e: the setting a user who must be sure of e
             would pick, read off the sweep. It equals first reach wherever the error falls
             monotonically with the tolerance, and it is never cheaper.

Both are reported (bench/wp/report.py); run.py re-times the two tools' decisive points of
each reading side by side (decisive_pairs).
"""

import statistics

LEVELS = (1e-3, 1e-6, 1e-9)  # the error levels of the summary tables
READINGS = ("first", "stays")
READING_TITLES = {"first": "first reach", "stays": "stays below"}


def is_kanesim(tool):
    return tool.startswith("kanesim")


def is_baseline(tool):
    """Not a simulator: a hand-derived minimal ODE (run.py: run_baseline); never "best peer"."""
    return tool.startswith("baseline")


def point_at(points, level, reading="first"):
    """The point a reading picks for error <= level, or None."""
    good = [pt for pt in points if pt.get("ok")]
    if reading == "stays":
        # The tight end of the sweep that stays below: the points tighter than the tightest
        # one above the level.
        above = [pt["param"] for pt in good if pt["error"] > level]
        if above:
            bound = min(above)
            good = [pt for pt in good if pt["param"] < bound]
    ok = [pt for pt in good if pt["error"] <= level]
    return min(ok, key=lambda pt: pt["time"]) if ok else None


def time_to(points, level, reading="first"):
    pt = point_at(points, level, reading)
    return pt["time"] if pt else None


def best_of(tools, level, reading, want_kanesim):
    """(time, tool, point) of the cheapest kanesim configuration (want_kanesim) or peer
    (baselines excluded) under a reading; (None, None, None) when none reaches the level."""
    best = (None, None, None)
    for tool, pts in tools.items():
        if is_kanesim(tool) != want_kanesim or (not want_kanesim and is_baseline(tool)):
            continue
        pt = point_at(pts, level, reading)
        if pt and (best[0] is None or pt["time"] < best[0]):
            best = (pt["time"], tool, pt)
    return best


def retimed_ratio(rec):
    """kanesim / peer of a decisive pair re-timed back to back (run.py retime_decisive,
    pairs.py): the ratio of the medians of the two sides' timings, failed runs (None) left
    out; None when a side has no timing."""
    tk = [t for t in rec["kanesim_times"] if t is not None]
    tp = [t for t in rec["peer_times"] if t is not None]
    return statistics.median(tk) / statistics.median(tp) if tk and tp else None
