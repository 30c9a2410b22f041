"""Which pipeline wins, for the generated READMEs (results_readme.py): per scene each series'
time over the fastest (geometric mean and range), wins and ties, counted like with like by
compare.py's rules, and the sweep's wins in one sentence that names its coverage.
Standard library only.
"""
from .compare import Tally, Verdict, contenders_with_overlap, geomean, ratios_tie, relative_spread
from .readme_format import table
from .sweep_rows import Series, by_setting


def fastest_text(cells, series):
    """'megakernel (wavefront 3.04×)': the fastest series and the others' time over its time, or
    'tie: megakernel, wavefront (1.01×)' when the fastest is within the frame spread of another
    (compare.py's rule)."""
    v = Verdict(cells)
    t = cells[v.fastest]["device_ms"]
    others = ", ".join(f"{series.label(k)} {cells[k]['device_ms'] / t:.2f}×"
                       for k in series.keys if k in cells and k != v.fastest)
    if v.is_tie:
        return f"tie: {', '.join(series.label(k) for k in v.tied)} ({others})"
    return f"{series.label(v.fastest)} ({others})" if others else series.label(v.fastest)


class SceneResult:
    """One scene's comparison over like with like (compare.py): the settings where every
    contender ran, each series' time over the fastest there, wins and ties."""

    def __init__(self, scene, settings, keys):
        self.scene = scene
        self.contenders, self.dropped = contenders_with_overlap(settings, keys)
        self.tally = Tally(settings, self.contenders)
        self.ratios = {k: [] for k in self.contenders}
        self.spreads = {k: [] for k in self.contenders}
        for cells in self.tally.complete:
            best = min(cells[k]["device_ms"] for k in self.contenders)
            for k in self.contenders:
                self.ratios[k].append(cells[k]["device_ms"] / best)
                self.spreads[k].append(relative_spread(cells[k]))
        self.g = {k: geomean(v) for k, v in self.ratios.items() if v}
        self.best = min(self.g, key=self.g.get) if self.g else None
        # Series whose mean time / fastest is within the frame spread of the best one's.
        self.level = [k for k in self.g if k == self.best or ratios_tie(
            self.g[k], self.g[self.best], self.spreads[k] + self.spreads[self.best])]

    def winner_text(self, label):
        if self.best is None:
            return "—"
        if len(self.level) > 1:
            return "tie: " + ", ".join(label(k) for k in sorted(self.level, key=self.g.get))
        return label(self.best)

    def coverage_note(self, label):
        """What the scene's counts leave out, in words; '' when every series ran everywhere."""
        parts = []
        text = self.tally.coverage_text(label, f" of {self.scene}")
        if text:
            parts.append(text)
        if self.dropped:
            parts.append(f"{', '.join(label(k) for k in self.dropped)}: no setting of "
                         f"{self.scene} where it and every other series ran; not counted.")
        return " ".join(parts)


def winners(rows):
    """(series, [SceneResult]) for every scene with a setting measured on two series or more."""
    series = Series(rows)
    by_scene = {}
    for k, cells in by_setting(rows, series):
        by_scene.setdefault(k[0], []).append(cells)
    return series, [SceneResult(scene, settings, series.keys)
                    for scene, settings in by_scene.items()]


def sweep_tally(rows):
    """(series, Tally) over every setting of the sweep measured on two series or more, counted
    where every series of the sweep ran."""
    series = Series(rows)
    settings = [cells for _, cells in by_setting(rows, series)]
    kept, _ = contenders_with_overlap(settings, series.keys)
    return series, Tally(settings, kept)


def tally_line(rows):
    """The sweep's wins in one sentence, like with like, ties apart; '' with one series."""
    series, t = sweep_tally(rows)
    if t.total == 0 or len(t.contenders) < 2:
        return ""
    cover = t.coverage_text(series.label)
    head = (f"Over all scenes: {t.total} settings compared. " + cover if cover else
            f"Over all scenes: every series ran in all {t.total} settings compared.")
    return f"{head} Wins: {t.wins_text(series.label)}."


def winner_table(rows):
    series, results = winners(rows)
    if not results:
        return "One series only: nothing to compare.", []
    body, notes = [], []
    for res in results:
        t = res.tally
        cols = []
        for k in series.keys:
            v = res.ratios.get(k)
            cols.append(f"{res.g[k]:.2f} ({min(v):.2f} – {max(v):.2f}), won {t.wins[k]}, "
                        f"tied {t.tied_for_fastest[k]}" if v else "—")
        compared = f"{t.n}" if t.n == t.total else f"{t.n} of {t.total}"
        body.append([res.scene, compared, t.ties] + cols + [res.winner_text(series.label)])
        if not t.n:
            continue
        best = res.best
        others = "; ".join(f"{series.label(k)} {res.g[k]:.2f}× the fastest time"
                           for k in series.keys if k in res.g and k != best)
        tie = (f" (level, within the frame spread, with "
               f"{', '.join(series.label(k) for k in res.level if k != best)})"
               if len(res.level) > 1 else "")
        notes.append(f"- **{res.scene}**: {series.label(best)}{tie}, fastest in {t.wins[best]} "
                     f"of {t.n} settings, {t.ties} tied"
                     + (f"; {others} (geometric mean)" if others else "") + "."
                     + (f" {res.coverage_note(series.label)}" if res.coverage_note(series.label)
                        else ""))
    head = (["Scene", "Settings compared", "Tied"]
            + [f"{series.label(k)}: time / fastest (geometric mean, range)" for k in series.keys]
            + ["Winner"])
    line = tally_line(rows)
    return table(head, body) + (f"\n\n{line}" if line else ""), notes
