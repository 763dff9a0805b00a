#!/usr/bin/env python3
"""ctest docs.links: every relative link and image in README.md, docs/*.md and tests/golden/README.md
resolves to a file or folder of the repository, and every #anchor to a heading of its target (GitHub's
heading ids). Web links are not fetched. Usage: check_links.py SOURCE_DIR"""
import glob, os, re, sys

source = sys.argv[1]
files = [os.path.join(source, "README.md"), os.path.join(source, "tests/golden/README.md")]
files += sorted(glob.glob(os.path.join(source, "docs/**/*.md"), recursive=True))
link = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def slug(heading):
    text = heading.strip().lower().replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path):
    ids, seen = set(), {}
    in_code = False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("```"):
                in_code = not in_code
            if in_code or not line.startswith("#"):
                continue
            base = slug(line.lstrip("#"))
            n = seen.get(base, 0)
            seen[base] = n + 1
            ids.add(base if n == 0 else f"{base}-{n}")
    return ids


failures, checked = [], 0
for md in files:
    in_code = False
    with open(md, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if line.startswith("```"):
                in_code = not in_code
            if in_code:
                continue
            for target in link.findall(line):
                if re.match(r"^[a-z]+:", target):
                    continue  # http:, https:, mailto:
                checked += 1
                path, _, anchor = target.partition("#")
                resolved = os.path.normpath(os.path.join(os.path.dirname(md), path)) if path else md
                where = f"{os.path.relpath(md, source)}:{number}: {target}"
                if not os.path.exists(resolved):
                    failures.append(f"{where}: no such file")
                elif not os.path.realpath(resolved).startswith(os.path.realpath(source)):
                    failures.append(f"{where}: outside the repository")
                elif anchor and resolved.endswith(".md") and anchor not in anchors(resolved):
                    failures.append(f"{where}: no heading with id #{anchor}")

for f in failures:
    print("FAIL", f)
print(f"{len(files)} files, {checked} links, {len(failures)} broken")
sys.exit(1 if failures else 0)
