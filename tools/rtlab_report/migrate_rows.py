"""One-off migration of committed sweep rows: adds the `failure` field, and
`pipeline_title` for the two pipelines that existed before rows carried it.

Usage: python3 -m rtlab_report migrate-rows results/*/*.json

Rows written before the field existed say how a cell failed only in English error text; the
charts and the generated READMEs now read the `failure` field alone, so this script derives it
once from the text: "" when the cell ran, else one of private_tree, tree_row, out_of_memory, opencl,
invalid_option, skipped, other. The CSV beside each JSON gets the same column. Edits are textual
(a line per row) so that numbers keep the digits the sweep wrote. Running it twice changes nothing.
"""
import csv
import io
import json
import os

TITLES = {"mega": "megakernel", "wave": "wavefront"}
KINDS = ("private_tree", "tree_row", "out_of_memory", "opencl", "invalid_option", "skipped",
         "timeout", "other")
# The few spellings the limits sweep used before the vocabulary was fixed.
OLD_KINDS = {"private tree": "private_tree", "tree row": "tree_row", "allocation": "out_of_memory",
             "OpenCL error": "opencl"}


def classify(row):
    """The failure kind of one row, from its status, an older `failure` value or its message."""
    status = row.get("status")
    if status == "ok":
        return ""
    if status == "skipped":
        return "skipped"
    old = row.get("failure", "")
    if old in KINDS:
        return old
    if old in OLD_KINDS:
        return OLD_KINDS[old]
    e = row.get("error", "")
    if "in private memory" in e:
        return "private_tree"
    if "one row of the wavefront ray tree" in e:
        return "tree_row"
    if any(s in e for s in ("ALLOCATION", "OUT_OF_RESOURCES", "OUT_OF_HOST_MEMORY",
                            "per allocation")):
        return "out_of_memory"
    if "CL_" in e:
        return "opencl"
    if "unknown option" in e or "invalid" in e:
        return "invalid_option"
    return "other"


def set_key(lines, start, end, key, value, after):
    """Sets `key` in one row object spanning lines[start:end] (keys at 3 spaces, sorted): replaces
    its line or inserts it after the line of `after`. Returns the new end."""
    text = f'   "{key}": {json.dumps(value, ensure_ascii=False)},'
    for i in range(start, end):
        if lines[i].startswith(f'   "{key}": '):
            lines[i] = text
            return end
    for i in range(start, end):
        if lines[i].startswith(f'   "{after}": '):
            lines.insert(i + 1, text)
            return end + 1
    raise ValueError(f"row at line {start + 1} has no {after!r} key")


def migrate_json(path):
    with open(path) as f:
        text = f.read()
    data = json.loads(text)
    if not isinstance(data, dict) or "rows" not in data:
        return None
    lines = text.split("\n")
    starts = [i for i, line in enumerate(lines) if line == "  {"]
    if len(starts) != len(data["rows"]):
        raise ValueError(f"{path}: {len(starts)} row objects in the text, {len(data['rows'])} rows")
    # From the last row up, so that insertions leave earlier indices valid.
    for n in reversed(range(len(starts))):
        row, start = data["rows"][n], starts[n]
        end = next(i for i in range(start, len(lines)) if lines[i].startswith("  }"))
        end = set_key(lines, start, end, "failure", classify(row), "error")
        if row["pipeline"] in TITLES and "pipeline_title" not in row:
            set_key(lines, start, end, "pipeline_title", TITLES[row["pipeline"]], "pipeline")
    out = "\n".join(lines)
    json.loads(out)  # still valid
    with open(path, "w") as f:
        f.write(out)
    return data["rows"]


def migrate_csv(path, rows):
    with open(path, newline="") as f:
        table = list(csv.reader(f))
    head, body = table[0], table[1:]
    if len(body) != len(rows):
        raise ValueError(f"{path}: {len(body)} lines, the JSON has {len(rows)} rows")
    if "failure" not in head:
        at = head.index("error") + 1
        head.insert(at, "failure")
        for line in body:
            line.insert(at, "")
    col = head.index("failure")
    for line, row in zip(body, rows):
        line[col] = classify(row)
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows([head] + body)
    with open(path, "w", newline="") as f:
        f.write(out.getvalue())


def main(argv=None):
    for path in argv or []:
        rows = migrate_json(path)
        if rows is None:
            print(f"migrate-rows: skipped {path} (not a sweep JSON)")
            continue
        csv_path = os.path.splitext(path)[0] + ".csv"
        if os.path.exists(csv_path):
            migrate_csv(csv_path, rows)
        print(f"migrate-rows: {path}: {len(rows)} rows")
    return 0

