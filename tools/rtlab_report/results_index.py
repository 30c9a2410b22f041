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
import io
import json
import lzma
import os
import re
import tarfile

DATA_ENDINGS = (".json", ".jsonl", ".jsonl.xz", ".csv", ".txt")
HEX = r"[0-9a-f]{7,40}"
QUOTED = re.compile(rf"`({HEX})`|\bcommits?\s+`?({HEX})\b")
LOGGED = re.compile(rf"\b(?:rtlab_)?commit[:=]?\s+({HEX})\b")
# Links, and paths in backticks ("(`../accels-2f20b57/`)"), that a README points at.
LINK = re.compile(r"\]\(([^)\s#]+)(?:#[^)\s]*)?\)|`(\.\.?/[^`\s]*)`")


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


def data_commits_of(name, data):
    """The commits the bytes of one data file, named name, carry (empty when unreadable)."""
    found = set()
    try:
        if name.endswith(".xz"):
            data, name = lzma.decompress(data), name[:-3]
        text = data.decode("utf-8", errors="replace")
        if name.endswith(".txt"):
            found |= {m.group(1).lower() for m in LOGGED.finditer(text)}
        elif name.endswith(".csv"):
            for row in csv.DictReader(io.StringIO(text, newline="")):
                if row.get("commit"):
                    found.add(row["commit"].lower())
        elif name.endswith(".json"):
            _commits_in(json.loads(text), found)
        else:
            for line in text.splitlines():
                if line.strip():
                    _commits_in(json.loads(line), found)
    except (ValueError, lzma.LZMAError, csv.Error):
        pass
    return found


def file_commits(path):
    """The commits one data file carries (empty when it cannot be read); an experiment's
    archive (results/archive/NAME.tar.xz): those of the data files inside it."""
    if path.endswith(".tar.xz"):
        return archive_commits(path)
    try:
        with open(path, "rb") as f:
            return data_commits_of(path, f.read())
    except OSError:
        return set()


_ARCHIVES = {}


def archive_commits(path):
    """The commits the data files inside a tarball carry (read once a run)."""
    key = os.path.abspath(path)
    if key not in _ARCHIVES:
        found = set()
        try:
            with tarfile.open(path, "r:xz") as tar:
                for m in tar:
                    if m.isfile() and m.name.endswith(DATA_ENDINGS):
                        found |= data_commits_of(m.name, tar.extractfile(m).read())
        except (OSError, tarfile.TarError, lzma.LZMAError):
            pass
        _ARCHIVES[key] = found
    return _ARCHIVES[key]


def page_archives(page):
    """The archives an experiment page (results/experiments/NAME.md) links to: its own first,
    then any whose data it draws on."""
    with open(page) as f:
        return [os.path.normpath(os.path.join(os.path.dirname(page), a))
                for a, _ in LINK.findall(f.read()) if a.endswith(".tar.xz")]


def page_archive(page):
    """The archive of an experiment page's own raw files, or None."""
    found = page_archives(page)
    return found[0] if found else None


def target_commits(target):
    """The commits behind a link into results/: a folder's data, a data file's, an experiment
    page's archive's, a README's folder's."""
    if os.path.isdir(target):
        return data_commits(target)
    folder, name = os.path.split(target)
    if os.path.basename(folder) == "experiments":
        # A page, or a chart beside it (NAME-chart.png): the archives the page links.
        page = next((os.path.join(folder, p) for p in sorted(os.listdir(folder), key=len,
                                                              reverse=True)
                     if p.endswith(".md") and (name == p or name.startswith(p[:-3] + "-"))), None)
        found = set()
        for archive in page_archives(page) if page else []:
            found |= archive_commits(archive) if os.path.exists(archive) else set()
        return found
    if not target.endswith(DATA_ENDINGS + (".tar.xz",)):
        # A README or a chart: its folder's data.
        return data_commits(folder)
    return file_commits(target)


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


def exists(target):
    """A link target that is there, or a README link whose folder is (the folder stands for it)."""
    return os.path.exists(target) or (target.endswith(".md") and
                                       os.path.isdir(os.path.dirname(target)))


def linked_data(readme, results):
    """The files and folders inside results/ a README links to."""
    here = os.path.dirname(os.path.abspath(readme))
    top = os.path.abspath(results)
    with open(readme) as f:
        targets = {os.path.normpath(os.path.join(here, a or b)) for a, b in LINK.findall(f.read())
                   if "://" not in (a or b)}
    return [t for t in targets if (t == top or t.startswith(top + os.sep)) and exists(t)]


def readme_commits(readme, results):
    """The commits a README's data carries: its folder's, and what it links to inside
    results/ (a link to another README: that README's folder; to an experiment's page: its
    archive)."""
    carried = data_commits(os.path.dirname(os.path.abspath(readme)))
    for target in linked_data(readme, results):
        carried |= target_commits(target)
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
