"""How two measured cells are compared, in one place: the tie rule, the verdict of a setting and
win counts over like with like. Every README table, win count, chart and the results index
(results_readme.py, readme_crossover.py, charts*.py, predict_eval.py, register_study.py) asks
this module, so that a "win" means the same thing everywhere.

The tie rule
    A cell's spread is the range of its timed frames, device_ms_max - device_ms_min (rows from
    before those fields: max - min of frame_ms; a row with neither has spread 0). Two cells TIE
    when their medians (device_ms) differ by no more than the larger of their two spreads: the
    gap is then inside what one cell's own frames already vary by, so the measurement does not
    say which is faster. Identical medians always tie. A setting has a WINNER only when its
    fastest cell ties with no other cell; otherwise it is tied, and every cell that ties with
    the fastest is "tied for fastest".
    Ratios (geometric means of time / fastest) use the same rule in relative form: two ratios tie
    when they differ by no more than the median relative spread (spread / median) of the cells
    behind them.

Like with like
    Wins are counted only over the settings where every contender ran. When one ran in fewer
    settings than the others, the count says so ("megakernel (weighted) ran in 12 of 48
    settings; counts are over those 12"), rather than crediting the others with the settings it
    missed.
Standard library only.
"""
import math
import statistics


def spread(r):
    """(fastest, slowest) timed frame of a row, in device ms."""
    lo, hi = r.get("device_ms_min"), r.get("device_ms_max")
    if lo is None or hi is None:
        frames = [f for f in (r.get("frame_ms") or []) if f is not None]
        lo, hi = (min(frames), max(frames)) if frames else (r["device_ms"], r["device_ms"])
    return lo, hi


def spread_ms(r):
    lo, hi = spread(r)
    return max(0.0, hi - lo)


def relative_spread(r):
    return spread_ms(r) / r["device_ms"] if r.get("device_ms") else 0.0


def tied(a, b):
    """True when rows a and b cannot be told apart: their medians differ by no more than the
    larger of their frame spreads."""
    return abs(a["device_ms"] - b["device_ms"]) <= max(spread_ms(a), spread_ms(b))


class Verdict:
    """The outcome of one setting, {series key: row} of the cells that ran.
    fastest: the key with the lowest median; winner: that key, or None when it ties another;
    tied: the keys that tie with the fastest (the fastest included), in time order;
    runner: the second fastest; margin: runner's median over the fastest's."""

    def __init__(self, cells):
        order = sorted(cells, key=lambda k: cells[k]["device_ms"])
        self.order = order
        self.fastest = order[0]
        best = cells[order[0]]
        self.tied = [k for k in order if k == order[0] or tied(best, cells[k])]
        self.winner = self.fastest if len(self.tied) == 1 else None
        self.runner = order[1] if len(order) > 1 else None
        self.margin = (cells[self.runner]["device_ms"] / best["device_ms"]
                       if self.runner and best["device_ms"] else 1.0)

    @property
    def is_tie(self):
        return self.winner is None


def ratios_tie(ga, gb, rel_spreads):
    """Two geometric means of time / fastest tie when they differ by no more than the median
    relative frame spread of the cells they are made of."""
    if not rel_spreads:
        return ga == gb
    lo, hi = sorted((ga, gb))
    return hi / lo - 1 <= statistics.median(rel_spreads)


class Tally:
    """Wins and ties over a list of settings ({key: row} each) for a fixed set of contenders,
    counted only where every contender ran."""

    def __init__(self, settings, contenders):
        self.contenders = list(contenders)
        self.total = len(settings)
        self.ran = {k: sum(1 for c in settings if k in c) for k in self.contenders}
        self.complete = [c for c in settings if all(k in c for k in self.contenders)]
        self.wins = {k: 0 for k in self.contenders}
        self.tied_for_fastest = {k: 0 for k in self.contenders}
        self.ties = 0
        for cells in self.complete:
            v = Verdict({k: cells[k] for k in self.contenders})
            if v.winner:
                self.wins[v.winner] += 1
            else:
                self.ties += 1
                for k in v.tied:
                    self.tied_for_fastest[k] += 1

    @property
    def n(self):
        return len(self.complete)

    def short(self):
        """Contenders that ran in fewer settings than the set holds."""
        return [k for k in self.contenders if self.ran[k] < self.total]

    def coverage_text(self, label, where=""):
        """'' when every contender ran everywhere, else which ran where and what is counted:
        'megakernel (weighted) ran in 12 of the 48 settings of cornell; counts and means are
        over those 12, where every series ran.'"""
        short = self.short()
        if not short:
            return ""
        parts = [f"{label(k)} ran in {self.ran[k]} of the {self.total} settings{where}"
                 for k in short]
        return f"{'; '.join(parts)}; counts and means are over the {self.n} where every series ran."

    def wins_text(self, label):
        """'megakernel (tree) fastest in 23, ...; tied in 9' over the complete settings."""
        order = sorted(self.contenders, key=lambda k: -self.wins[k])
        text = ", ".join(f"{label(k)} fastest in {self.wins[k]}" for k in order)
        return text + f"; tied (within the frame spread) in {self.ties}"


def contenders_with_overlap(settings, keys):
    """The contenders to count: every key that ran in these settings, less those (fewest
    settings first) without which no setting has them all. Returns (kept, dropped)."""
    ran = {k: sum(1 for c in settings if k in c) for k in keys}
    kept = [k for k in keys if ran[k]]
    dropped = [k for k in keys if not ran[k]]
    while len(kept) > 2 and not any(all(k in c for k in kept) for c in settings):
        least = min(kept, key=lambda k: ran[k])
        kept.remove(least)
        dropped.append(least)
    return kept, dropped


def geomean(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


PARETO_RTOL = 0.01
# Errors are compared exactly, and where they differ only past this many decimal places (float
# rounding of the same image), said so apart: never folded into "equal".
ERROR_DECIMALS = 9


def error_setting(r):
    return (r["scene"], r["width"], r["height"], r["bounces"], r["shadow_samples"], r["aa"],
            r.get("accel"))


def error_agreement(rows):
    """How alike the designs' errors are, over the settings scored on more than one series:
    {"settings": n, "equal": exactly equal RMSE, "rounded": equal only once rounded to
    ERROR_DECIMALS decimal places, "differ": the rest, "worst": the largest relative gap}."""
    by = {}
    for r in rows:
        if r.get("rmse") is not None:
            by.setdefault(error_setting(r), []).append(r["rmse"])
    out = {"settings": 0, "equal": 0, "rounded": 0, "differ": 0, "worst": 0.0}
    for v in by.values():
        if len(v) < 2:
            continue
        out["settings"] += 1
        if max(v) == min(v):
            out["equal"] += 1
        elif len({round(x, ERROR_DECIMALS) for x in v}) == 1:
            out["rounded"] += 1
        else:
            out["differ"] += 1
        if max(v) > 0:
            out["worst"] = max(out["worst"], (max(v) - min(v)) / max(v))
    return out


def agreement_text(a):
    """One sentence of error_agreement's counts, exact equality kept apart from rounding."""
    if not a["settings"]:
        return ""
    return (f"The designs' errors are exactly equal in {a['equal']} of the {a['settings']} "
            f"settings scored on more than one, equal once rounded to {ERROR_DECIMALS} decimal "
            f"places (not exactly) in {a['rounded']} more, and differ beyond that in "
            f"{a['differ']} (largest relative gap {a['worst']:.2g}).")


def pareto(points, rtol=PARETO_RTOL):
    """Points (time, error, ...) not beaten on both axes, by increasing time. A point joins the
    front only when it cuts the error by more than rtol (relative) below the last point on it:
    errors that agree to 1% (often the same image from two pipelines, equal but for float
    rounding) are one level of accuracy, and the faster of them holds it."""
    front, best = [], float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best * (1 - rtol):
            front.append(p)
            best = p[1]
    return front
