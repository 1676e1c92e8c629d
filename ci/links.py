#!/usr/bin/env python3
"""Every relative link and code path in the README, BENCHMARKS.md and the book points at
something that exists.

    ci/links.py FILE_OR_DIR...

Checked in each Markdown file (a folder: every `.md` below it):
- links `[text](target)` that are not URLs: the file or folder exists (relative to the file),
  and a `#anchor` names a heading of that Markdown file;
- paths written as code, `` `host/io/src/ros/bag.rs` ``: a backquoted word with a slash and no
  spaces that looks like a repository path (it starts with a top-level folder of this
  repository, or `../shared/`) exists.
Exits 1 listing what is missing.
"""

import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")
CODE = re.compile(r"`([^`\s]+/[^`\s]*)`")
FENCE = re.compile(r"^(```|~~~)")


def anchors(md: Path) -> set:
    """GitHub/mdBook heading anchors of a Markdown file."""
    out = set()
    fenced = False
    for line in md.read_text().splitlines():
        if FENCE.match(line):
            fenced = not fenced
        m = re.match(r"^#{1,6}\s+(.*)$", line)
        if m and not fenced:
            text = re.sub(r"[`*_]", "", m.group(1)).strip().lower()
            out.add(re.sub(r"[^\w\- ]", "", text).replace(" ", "-"))
    return out


def top_level() -> set:
    # `target/` and `dist/` hold what builds and CI make: not there on a clean clone.
    made = {"target", "dist"}
    return {p.name for p in REPO.iterdir() if not p.name.startswith(".")} - made | {".ci"}


def check(md: Path, roots: set) -> list:
    problems = []
    fenced = False
    for n, line in enumerate(md.read_text().splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        for m in LINK.finditer(line):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z]+:", target) or target.startswith("mailto:"):
                continue
            path, _, anchor = target.partition("#")
            dest = (md.parent / path).resolve() if path else md
            if not dest.exists():
                problems.append(f"{md}:{n}: link to {target}: no such file")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                problems.append(f"{md}:{n}: link to {target}: no such heading")
        if fenced:
            continue
        for m in CODE.finditer(line):
            word = m.group(1).rstrip(".,:;").split("::")[0]
            first = word.split("/")[0]
            if "*" in word or "{" in word or "<" in word or "NNN" in word or "XX" in word:
                continue
            if first == ".." and word.startswith("../shared/"):
                if not (REPO.parent / word[3:]).exists():
                    problems.append(f"{md}:{n}: {word}: no such path beside the repository")
            elif first in roots and not (REPO / word).exists():
                problems.append(f"{md}:{n}: {word}: no such path in the repository")
    return problems


def main(args) -> int:
    roots = top_level()
    files = []
    for a in args:
        p = Path(a)
        files += sorted(p.rglob("*.md")) if p.is_dir() else [p]
    problems = [x for f in files for x in check(f, roots)]
    for p in problems:
        print(p)
    print(f"links: {len(files)} files checked, {len(problems)} broken")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
