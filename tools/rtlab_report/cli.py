"""The commands of rtlab_report, one a step of the report: each runs one module's main() with
the rest of the command line (`python3 -m rtlab_report COMMAND --help` for its options).
Modules are imported only when their command runs, so the table-only commands work without
matplotlib."""
import importlib
import sys

# command: (module, what it does)
COMMANDS = {
    "charts": ("charts", "a sweep's charts (time, memory, kernels, accuracy, limits, crossover)"),
    "readme": ("results_readme", "a device folder's README from its sweeps; with --index, or "
               "given results/, the results index too"),
    "map-charts": ("charts_map", "the crossover map: which design wins each wall"),
    "persist-charts": ("charts_persist", "the persistent megakernel against the others"),
    "phase-charts": ("charts_phases", "the persistent megakernel's phase clocks in ms"),
    "occupancy-charts": ("charts_occupancy", "busy lanes and warps of the occupancy sweeps"),
    "predict": ("predict_eval", "how often `rtlab predict` names the winner, at the shipped "
                "threshold; fit and test sets apart"),
    "auto-eval": ("auto_eval", "auto against the best design of each setting"),
    "register-study": ("register_study", "the register study's table (scripts/register-study)"),
    "migrate-rows": ("migrate_rows", "rewrite old sweep JSON and CSV to the current row format"),
    "experiment": ("experiments", "archive an experiment's folders into results/archive/ and "
                   "draft its page in results/experiments/"),
    "check-results": ("results_check", "results/ against its index and README.md's commits"),
    "acne-study": ("acne_study", "issue 51: acne rates of each --offset rule against the oracle, "
                   "before and after a change, at three scales"),
    "acne-pairs": ("acne_pairs", "issue 51 on a GPU run of bench/sweeps/acne: each floor as "
                   "triangles against the same floor as a plane"),
    "kernel-ab": ("kernel_ab", "scripts/gpu-kernel-ab's rounds: A against B, ties inside the "
                  "spread"),
}


def usage():
    lines = ["usage: python3 -m rtlab_report COMMAND [ARGS...]", "", "commands:"]
    lines += [f"  {name:<17} {text}" for name, (_, text) in COMMANDS.items()]
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("help", "-h", "--help"):
        print(usage())
        return 0
    if argv[0] not in COMMANDS:
        print(f"rtlab_report: no command '{argv[0]}'\n\n{usage()}", file=sys.stderr)
        return 2
    module = importlib.import_module(f"rtlab_report.{COMMANDS[argv[0]][0]}")
    sys.argv[0] = f"rtlab_report {argv[0]}"
    return module.main(argv[1:]) or 0
