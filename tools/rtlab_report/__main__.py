"""`python3 -m rtlab_report COMMAND` and `python3 tools/rtlab_report COMMAND` (run as a folder,
the package is not yet importable: its parent goes on the path first)."""
import os
import sys

if not __package__:
    sys.path[0] = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from rtlab_report.cli import main  # noqa: E402

sys.exit(main())
