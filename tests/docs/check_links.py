#!/usr/bin/env python3
"""Checks the links of the README and docs/*.md: every relative link names a file or folder of the repository, every
#anchor a heading of its page (GitHub's slugs), and no link leaves the repository. Exit 0 when all resolve, 1 with
one line per broken link otherwise.

Usage: tests/docs/check_links.py [REPOSITORY_ROOT]   (default: two folders above this script)
"""
import os
import re
import sys

# [text](target) and [text](target "title"); images too. Reference-style links are not used in these pages.
LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")


def strip_code(lines):
    """The lines outside fenced code blocks, with inline code spans blanked (links in code are not links)."""
    out = []
    fenced = False
    for line in lines:
        if FENCE.match(line):
            fenced = not fenced
            out.append("")
            continue
        out.append("" if fenced else re.sub(r"`[^`]*`", "``", line))
    return out


def slug(heading):
    """GitHub's anchor for a heading: markup dropped, lower case, punctuation removed, spaces → hyphens."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link's text only
    text = text.replace("`", "").replace("*", "")
    text = re.sub(r"(?<!\w)_|_(?!\w)", "", text)
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)  # \w keeps letters and digits of any script, and "_"
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        found = set()
        counts = {}
        with open(path, encoding="utf-8") as f:
            for line in strip_code(f.read().splitlines()):
                m = HEADING.match(line)
                if not m:
                    continue
                base = slug(m.group(2))
                n = counts.get(base, 0)
                counts[base] = n + 1
                found.add(base if n == 0 else f"{base}-{n}")
        cache[path] = found
    return cache[path]


def check(root, page):
    errors = []
    with open(page, encoding="utf-8") as f:
        lines = strip_code(f.read().splitlines())
    for number, line in enumerate(lines, 1):
        for m in LINK.finditer(line):
            target = m.group(1)
            where = f"{os.path.relpath(page, root)}:{number}: {target}"
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                if not target.startswith(("http://", "https://", "mailto:")):
                    errors.append(f"{where}: not a relative link or a web address")
                continue
            path_part, _, anchor = target.partition("#")
            if path_part.startswith("/"):
                errors.append(f"{where}: absolute path (links must be relative)")
                continue
            resolved = os.path.normpath(os.path.join(os.path.dirname(page), path_part)) if path_part else page
            if os.path.relpath(resolved, root).startswith(".."):
                errors.append(f"{where}: leaves the repository")
                continue
            if not os.path.exists(resolved):
                errors.append(f"{where}: no such file")
                continue
            if anchor:
                if not resolved.endswith(".md"):
                    errors.append(f"{where}: an anchor into a file that is not Markdown")
                elif anchor not in anchors(resolved):
                    errors.append(f"{where}: no heading with the anchor #{anchor} in {os.path.relpath(resolved, root)}")
    return errors


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
    docs = os.path.join(root, "docs")
    pages = [os.path.join(root, "README.md")]
    pages += sorted(os.path.join(docs, n) for n in os.listdir(docs) if n.endswith(".md"))
    errors = []
    links = 0
    for page in pages:
        with open(page, encoding="utf-8") as f:
            links += sum(len(LINK.findall(l)) for l in strip_code(f.read().splitlines()))
        errors += check(root, page)
    for e in errors:
        print(e)
    print(f"check_links: {len(pages)} pages, {links} links, {len(errors)} broken")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
