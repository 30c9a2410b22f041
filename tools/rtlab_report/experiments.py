"""The experiments behind the published sets, out of results/' main listing: each one's raw
files go into one tarball, results/archive/NAME.tar.xz (patch files left out: they stay in git
history), and a page, results/experiments/NAME.md, says what it asked, on what, at which commit,
what it found and where its raw data is.

Usage: python3 -m rtlab_report experiment RESULTS NAME PATH... [--base COMMIT] [--into DIR]
    PATH: folders or files under RESULTS (results/, or where a sweep was imported with
    RTLAB_RESULTS_DIR); the archive and the page go into --into [RESULTS]; the first one's README.md (or the file itself, when it
    is a note) gives the page its title, setting and findings. --base names the commit whose
    tree still holds the files as they were, patches included. Remove the PATHs afterwards
    (git rm -r); the tool only writes.

The page is a draft drawn from the experiment's own README: its first heading (the question),
its first paragraph (the setting), and its paragraphs with bold figures (the finding). The full
README travels in the tarball.
Standard library only.
"""
import argparse
import io
import os
import re
import sys
import tarfile

from . import results_index

PATCH_ENDINGS = (".patch", ".diff")


def members(results, paths):
    """Every file under the paths, relative to results/, sorted; patch files left out."""
    out = []
    for p in paths:
        full = os.path.join(results, p)
        if os.path.isfile(full):
            out.append(p)
            continue
        for path, dirs, files in os.walk(full):
            dirs.sort()
            for name in sorted(files):
                rel = os.path.relpath(os.path.join(path, name), results).replace(os.sep, "/")
                if not name.endswith(PATCH_ENDINGS):
                    out.append(rel)
    return out


def write_archive(results, name, files, into=None):
    """INTO/archive/NAME.tar.xz of the files, byte for byte the same on every run (sorted
    members, no owners, no times), so that re-archiving does not churn history."""
    into = into or results
    os.makedirs(os.path.join(into, "archive"), exist_ok=True)
    path = os.path.join(into, "archive", name + ".tar.xz")
    with tarfile.open(path, "w:xz", preset=9, format=tarfile.PAX_FORMAT) as tar:
        for rel in files:
            with open(os.path.join(results, rel), "rb") as f:
                data = f.read()
            info = tarfile.TarInfo(rel)
            info.size, info.mtime, info.mode = len(data), 0, 0o644
            tar.addfile(info, io.BytesIO(data))
    return path


def paragraphs(text):
    """The text's paragraphs (blank-line separated), headings, quotes and code left out."""
    out, code = [], False
    for block in re.split(r"\n\s*\n", text):
        if block.lstrip().startswith("```"):
            code = not code if block.count("```") % 2 else code
            continue
        if code or block.lstrip().startswith(("#", ">", "![")):
            continue
        out.append(block.strip())
    return [p for p in out if p]


def draft(readme_text, fallback_title):
    """(title, setting, [finding paragraphs]) from an experiment's README."""
    title = next((line.lstrip("#").strip() for line in readme_text.splitlines()
                  if line.startswith("#")), fallback_title)
    paras = paragraphs(readme_text)
    prose = [p for p in paras if not p.startswith("|")]
    setting = prose[0] if prose else ""
    bold = [p for p in prose[1:] if "**" in p]
    finding = bold[:3] or prose[1:3]
    return title, setting, finding


def relink(text, old_dir, new_dir):
    """Relative links of a text written in old_dir, made to work from new_dir (links that
    point inside the archived folders then name a file of the tarball, said so in the page)."""
    def fix(m):
        target = m.group(2)
        if "://" in target or target.startswith(("#", "/")):
            return m.group(0)
        moved = os.path.relpath(os.path.normpath(os.path.join(old_dir, target)), new_dir)
        return f"{m.group(1)}({moved.replace(os.sep, '/')})"
    return re.sub(r"(\]\s*)\(([^)\s]+)\)", fix, text)


def page(results, name, paths, files, base, into=None):
    first = os.path.join(results, paths[0])
    source = os.path.join(first, "README.md") if os.path.isdir(first) else first
    text = ""
    if os.path.exists(source) and source.endswith((".md", ".txt")):
        with open(source, errors="replace") as f:
            text = f.read()
    if source.endswith(".txt"):
        # A tool's printout: its first line says what ran; the whole of it, verbatim, is the
        # finding (a page must not reflow a table of columns).
        title, setting, finding = name, text.splitlines()[0] if text else "", \
            ["```\n" + text.rstrip() + "\n```"]
    else:
        title, setting, finding = draft(text, name)
    pages = os.path.join(into or results, "experiments")
    old = os.path.dirname(source)
    setting, finding = relink(setting, old, pages), [relink(p, old, pages) for p in finding]
    device = paths[0].split("/")[0]
    commits = set()
    for rel in files:
        if rel.endswith(results_index.DATA_ENDINGS):
            commits |= results_index.file_commits(os.path.join(results, rel))
    shown = sorted({c[:7] for c in commits})
    where = ", ".join(f"`{p}`" for p in paths)
    # The title is the question the experiment asked.
    lines = [f"# {title}", "",
             "- **Device**: " + (f"[`{device}`](../{device}/README.md)."
                                  if os.path.exists(os.path.join(into or results, device,
                                                                 "README.md"))
                                  else f"`{device}` (no published set of its own)."),
             "- **Commits in the data**: " + (", ".join(f"`{c}`" for c in shown) or "none recorded")
             + ".",
             f"- **Raw data**: [`archive/{name}.tar.xz`](../archive/{name}.tar.xz), {len(files)} "
             f"files, once {where} (`tar -xJf results/archive/{name}.tar.xz` puts them back)"
             + (f"; patch files, and the files as committed, in git history at `{base}`"
                if base else "") + ".",
             "", "## Setting", "", setting or "See the README in the archive.", "",
             "## Finding", ""]
    lines += [p + "\n" for p in finding] or ["See the README in the archive.\n"]
    os.makedirs(pages, exist_ok=True)
    path = os.path.join(pages, name + ".md")
    with open(path, "w") as f:
        f.write("\n".join(lines).rstrip() + "\n")
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results")
    ap.add_argument("name")
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--base", default="")
    ap.add_argument("--into", help="the results folder that gets the archive and page [RESULTS]")
    a = ap.parse_args(argv)
    files = members(a.results, a.paths)
    if not files:
        sys.exit(f"experiment: nothing under {a.paths}")
    archive = write_archive(a.results, a.name, files, a.into)
    doc = page(a.results, a.name, a.paths, files, a.base, a.into)
    print(f"experiment {a.name}: {len(files)} files, {os.path.getsize(archive) // 1024} KiB; {doc}")
