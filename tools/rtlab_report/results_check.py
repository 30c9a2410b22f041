"""results/ against its index, its archives and the commits the READMEs quote; the test
(tests/python/test_results_index.py) and `python3 -m rtlab_report check-results` ask this.

What results/ must be
    At the top: README.md (the index), one folder a device kind (its published set, with its
    README), experiments/ (one page an experiment) and archive/ (one NAME.tar.xz an
    experiment). The index names every top-level entry and every experiment page; every page
    links its archive, which exists, and every archive has a page. No patch file (.patch, .diff)
    anywhere under results/, in an archive neither: the code an experiment ran is in git history.
What the commits must be
    A commit a README quotes (`5af2c8e`, "commit 5af2c8e", "at 5af2c8e" in backticks) must be
    one the data it links into results/ records. In the repository's README.md the rule holds
    per block (a paragraph or a list item): a quote must be recorded by the data the same block
    links to; a block that links into results/ nowhere is held to every results/ link of the
    README. A commit a page lists under "Commits in the data" must be in its archive's data.
Standard library only.
"""
import json
import os
import re
import tarfile

from . import results_index

PATCH_ENDINGS = (".patch", ".diff")

# Commits the READMEs of results/ name that no data under them records: code history (the fix
# a generated limits table names). Any new unrecorded quote fails; an entry that becomes
# recorded fails too, and must then leave the list.
NOT_IN_DATA = {
    ("nvidia-h200/README.md", "ed93f1e"),
}
# Commits the repository's README names as history, not as a measurement of results/: the
# set a re-measured one replaced (in git history only). The README is rewritten often: an
# entry it no longer quotes is no failure here.
README_HISTORY = {
    "9662d72",  # the tree wavefront before its fix; `git show 791a156:results/...`
    "1ecf30d",  # the PoCL limits sweep before the launch planner, replaced at 253768c
}

AT_COMMIT = re.compile(r"\bat\s+`?([0-9a-f]{7,40})\b")


def read(path):
    with open(path) as f:
        return f.read()


# Device folders whose published set is not yet at one commit: the sweeps were measured at
# several, and the final measurement at one commit replaces them. A folder that reaches one
# commit fails the test until it leaves this list; a new folder must be at one commit.
NOT_YET_ONE_COMMIT = {
    "nvidia-h100-80gb-hbm3",                 # full at 3ad6d1e, limits at a664cec
    "nvidia-h200",                           # full at 5af2c8e, crossover at b05cbeb, 8380cd2
    "pocl-pthread-skylake-avx512-amd-epyc",  # cpu, crossover-cpu, limits, queue-launch-cpu
}


def set_commits(results):
    """{device folder: the commits its sweeps' metadata records} (the `commit` of each
    NAME.json's meta at the folder's top)."""
    out = {}
    for slug in top_entries(results):
        folder = os.path.join(results, slug)
        if slug in ("experiments", "archive") or not os.path.isdir(folder):
            continue
        found = set()
        for name in sorted(os.listdir(folder)):
            if not name.endswith(".json"):
                continue
            try:
                with open(os.path.join(folder, name)) as f:
                    data = json.load(f)
            except (OSError, ValueError):
                continue
            if isinstance(data, dict) and "meta" in data and "rows" in data:
                found.add(str(data["meta"].get("commit", "?"))[:7])
        out[slug] = found
    return out


def top_entries(results):
    return sorted(e for e in os.listdir(results) if e != "README.md" and not e.startswith("."))


def named_in(text):
    """Paths the index names: link targets and backticked paths, without a trailing / or
    README.md."""
    names = set(re.findall(r"\]\(([^)\s#]+)", text)) | set(re.findall(r"`([^`\s]+)`", text))
    out = set()
    for n in names:
        n = n.rstrip("/")
        out |= {n, n[:-len("/README.md")] if n.endswith("/README.md") else n}
    return out


def pages(results):
    folder = os.path.join(results, "experiments")
    return sorted(n[:-3] for n in os.listdir(folder) if n.endswith(".md")) \
        if os.path.isdir(folder) else []


def archives(results):
    folder = os.path.join(results, "archive")
    return sorted(n[:-7] for n in os.listdir(folder) if n.endswith(".tar.xz")) \
        if os.path.isdir(folder) else []


def index_problems(results):
    """[text] for each way results/ and its index disagree."""
    out = []
    index = os.path.join(results, "README.md")
    named = named_in(read(index)) if os.path.exists(index) else set()
    out += [f"results/README.md does not name {e}" for e in top_entries(results)
            if e not in named]
    out += [f"results/README.md does not link experiments/{p}.md" for p in pages(results)
            if f"experiments/{p}.md" not in named]
    for p in pages(results):
        archive = results_index.page_archive(os.path.join(results, "experiments", p + ".md"))
        if not archive or not os.path.exists(archive):
            out.append(f"experiments/{p}.md links no archive that exists")
    out += [f"archive/{a}.tar.xz has no page experiments/{a}.md" for a in archives(results)
            if a not in pages(results)]
    for path, dirs, files in os.walk(results):
        out += [f"patch file {os.path.relpath(os.path.join(path, n), results)}" for n in files
                if n.endswith(PATCH_ENDINGS)]
    for a in archives(results):
        with tarfile.open(os.path.join(results, "archive", a + ".tar.xz"), "r:xz") as tar:
            out += [f"patch file {m.name} in archive/{a}.tar.xz" for m in tar
                    if m.name.endswith(PATCH_ENDINGS)]
    return out


def quotes(text):
    """The commits a text quotes: results_index's rule, and "at `5af2c8e`" / "at 5af2c8e"."""
    out = results_index.quoted_commits(text)
    return out + [h for h in AT_COMMIT.findall(text) if not h.isdigit() and h not in out]


def blocks(text):
    """Paragraphs and list items, code blocks left out."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    out = []
    for para in re.split(r"\n\s*\n", text):
        out += [b for b in re.split(r"\n(?=\s*(?:[-*]|\d+\.)\s)", para) if b.strip()]
    return out


def links_into(block, here, results):
    top = os.path.abspath(results)
    targets = {os.path.normpath(os.path.join(here, a or b))
               for a, b in results_index.LINK.findall(block) if "://" not in (a or b)}
    return [t for t in targets if (t == top or t.startswith(top + os.sep)) and
            results_index.exists(t)]


def carried(targets):
    found = set()
    for t in targets:
        found |= results_index.target_commits(t)
    return found


def readme_quote_problems(readme, results):
    """[(commit, the block's first words)] for each commit the README quotes that the data it
    links into results/ does not record (per block; see the module's note)."""
    here = os.path.dirname(os.path.abspath(readme))
    text = read(readme)
    everything = carried(links_into(text, here, results))
    out = []
    for block in blocks(text):
        qs = quotes(block)
        if not qs:
            continue
        own = links_into(block, here, results)
        data = carried(own) if own else everything
        out += [(q, " ".join(block.split()[:8])) for q in qs
                if not any(c.startswith(q) for c in data)]
    return out


def page_problems(results):
    out = []
    for p in pages(results):
        path = os.path.join(results, "experiments", p + ".md")
        line = next((line for line in read(path).splitlines()
                     if "Commits in the data" in line), "")
        archive = results_index.page_archive(path)
        data = results_index.archive_commits(archive) if archive else set()
        out += [f"experiments/{p}.md lists {q}, not in its archive's data"
                for q in re.findall(r"`([0-9a-f]{7,40})`", line)
                if not any(c.startswith(q) for c in data)]
    return out


def main(argv=None):
    argv = argv or []
    root = argv[0] if argv else "."
    results = os.path.join(root, "results")
    problems = index_problems(results) + page_problems(results)
    problems += [f"{slug}: its sweeps are at {len(c)} commits ({', '.join(sorted(c))}), not one"
                 for slug, c in set_commits(results).items()
                 if len(c) > 1 and slug not in NOT_YET_ONE_COMMIT]
    problems += [f"{r}: quotes {c}, not in its data"
                 for r, c in results_index.readme_problems(results) if (r, c) not in NOT_IN_DATA]
    problems += [f"README.md: quotes {c} in \"{where} ...\", not in the data it links"
                 for c, where in readme_quote_problems(os.path.join(root, "README.md"), results)
                 if c not in README_HISTORY]
    for p in problems:
        print(p)
    print(f"check-results: {len(problems)} problems")
    return 1 if problems else 0
