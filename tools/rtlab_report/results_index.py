"""What results/ holds, for the index results_readme.py writes and for the test that keeps the
index and the READMEs honest (tests/python/test_results_index.py): every result folder, the
commits its data carries, and the commits its README quotes.

A folder's data is every JSON, JSON-lines (also .jsonl.xz) and CSV file under it, and the logs
the tools wrote there (.txt); the commits it carries are the values of every "commit" field in
the data files (rows, sweep metadata, benchmark reports) at any depth, and the "commit <hex>" /
"rtlab_commit: <hex>" a tool printed in a log or a note in the data names. A README's data is
its folder's, and that of the files and folders inside results/ it links to (a link to another
README: that README's folder). A README quotes a commit where it writes a hex
string of 7 to 40 digits in backticks (`8380cd2`) or after the word "commit" (commit 8380cd2);
a quote matches a carried commit it is a prefix of.
Standard library only.
"""
import csv
import json
import lzma
import os
import re

DATA_ENDINGS = (".json", ".jsonl", ".jsonl.xz", ".csv", ".txt")
HEX = r"[0-9a-f]{7,40}"
QUOTED = re.compile(rf"`({HEX})`|\bcommits?\s+`?({HEX})\b")
LOGGED = re.compile(rf"\b(?:rtlab_)?commit[:=]?\s+({HEX})\b")
# Links, and paths in backticks ("(`../accels-2f20b57/`)"), that a README points at.
LINK = re.compile(r"\]\(([^)\s#]+)\)|`(\.\.?/[^`\s]*)`")


def folders(results):
    """Every folder under results/, as paths relative to it, sorted."""
    out = []
    for path, dirs, _ in os.walk(results):
        dirs.sort()
        rel = os.path.relpath(path, results)
        if rel != ".":
            out.append(rel.replace(os.sep, "/"))
    return sorted(out)


def _commits_in(value, found):
    if isinstance(value, dict):
        for k, v in value.items():
            if k == "commit" and isinstance(v, str):
                found.add(v.lower())
            else:
                _commits_in(v, found)
    elif isinstance(value, str):
        # A note written into the data ("the kernel tree of commit d0b4c82").
        found |= {m.group(1).lower() for m in LOGGED.finditer(value)}
    elif isinstance(value, list):
        for v in value:
            _commits_in(v, found)


def file_commits(path):
    """The commits one data file carries (empty when it cannot be read)."""
    found = set()
    try:
        if path.endswith(".txt"):
            with open(path, errors="replace") as f:
                found |= {m.group(1).lower() for m in LOGGED.finditer(f.read())}
        elif path.endswith(".csv"):
            with open(path, newline="") as f:
                for row in csv.DictReader(f):
                    if row.get("commit"):
                        found.add(row["commit"].lower())
        elif path.endswith(".json"):
            with open(path) as f:
                _commits_in(json.load(f), found)
        else:
            opener = lzma.open if path.endswith(".xz") else open
            with opener(path, "rt") as f:
                for line in f:
                    if line.strip():
                        _commits_in(json.loads(line), found)
    except (OSError, ValueError, lzma.LZMAError, UnicodeDecodeError, csv.Error):
        pass
    return found


def data_commits(folder, recursive=True):
    """The commits the data files in a folder (and, recursively, under it) carry."""
    found = set()
    for path, dirs, files in os.walk(folder):
        for name in files:
            if name.endswith(DATA_ENDINGS):
                found |= file_commits(os.path.join(path, name))
        if not recursive:
            break
    return found


def quoted_commits(text):
    """The hex strings a README quotes as commits, in order, each once. All-digit strings
    (run ids, timestamps) are not commits."""
    out = []
    for m in QUOTED.finditer(text):
        h = m.group(1) or m.group(2)
        if not h.isdigit() and h not in out:
            out.append(h)
    return out


def unbacked_quotes(readme, carried):
    """The commits a README quotes that no commit in `carried` begins with."""
    with open(readme) as f:
        quotes = quoted_commits(f.read())
    return [q for q in quotes if not any(c.startswith(q) for c in carried)]


def linked_data(readme, results):
    """The files and folders inside results/ a README links to."""
    here = os.path.dirname(os.path.abspath(readme))
    top = os.path.abspath(results)
    with open(readme) as f:
        targets = {os.path.normpath(os.path.join(here, a or b)) for a, b in LINK.findall(f.read())
                   if "://" not in (a or b)}
    # A link to another README stands for the folder it describes.
    targets = {os.path.dirname(t) if t.endswith(".md") else t for t in targets}
    return [t for t in targets if (t == top or t.startswith(top + os.sep)) and os.path.exists(t)]


def readme_commits(readme, results):
    """The commits a README's data carries: its folder's, and what it links to inside
    results/."""
    carried = data_commits(os.path.dirname(os.path.abspath(readme)))
    for target in linked_data(readme, results):
        carried |= data_commits(target) if os.path.isdir(target) else file_commits(target)
    return carried


def readme_problems(results):
    """[(README path relative to results/, commit)] for every quote none of the README's data
    carries."""
    out = []
    for rel in [""] + folders(results):
        readme = os.path.join(results, rel, "README.md")
        if os.path.exists(readme):
            carried = readme_commits(readme, results)
            out += [(os.path.normpath(os.path.join(rel, "README.md")), q)
                    for q in unbacked_quotes(readme, carried)]
    return out


def missing_from_index(results):
    """Folders under results/ that results/README.md does not name (as a link or in backticks)."""
    index = os.path.join(results, "README.md")
    text = ""
    if os.path.exists(index):
        with open(index) as f:
            text = f.read()
    named = set(re.findall(r"\]\(([^)\s]+?)/?(?:README\.md)?\)", text))
    named |= {t.rstrip("/") for t in re.findall(r"`([^`\s]+)`", text)}
    return [f for f in folders(results) if f not in named]


def readme_of(results, rel):
    """The README that describes a folder: its own, else the nearest one above it."""
    parts = rel.split("/")
    while parts:
        candidate = "/".join(parts + ["README.md"])
        if os.path.exists(os.path.join(results, candidate)):
            return candidate
        parts.pop()
    return "README.md"


def title_of(results, rel):
    """The first heading of a folder's own README, else ''."""
    path = os.path.join(results, rel, "README.md")
    if not os.path.exists(path):
        return ""
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                return line.lstrip("#").strip()
    return ""
