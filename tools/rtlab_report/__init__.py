"""rtlab_report: the report side of rtlab, from measured sweep rows to charts, result READMEs,
the results/ index and the studies' evaluations. One entry point, `python3 -m rtlab_report
COMMAND` (with tools/ on the path) or `python3 tools/rtlab_report COMMAND`; `help` lists the
commands (cli.py). The rows come from `rtlab sweep` (sweep_rows.py reads them); a win, a tie and
an equal error mean the same thing in every command (compare.py); every chart takes its colours
from one palette (chart_style.py).
Tables, READMEs and the index need the standard library only; charts need Debian's
python3-matplotlib (scripts/setup), hence /usr/bin/python3.
"""
