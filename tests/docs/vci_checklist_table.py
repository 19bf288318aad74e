"""docs/vci.md's "Checklist coverage" table against the tests: a row for every item 1..132 of
the VCI digest's checklist, in order, each naming at least one test through an API, and every
test it names (file:Suite.Test) defined in that file under tests/system/. A row may instead say
why an item has no test ("not testable: ...").

Usage: vci_checklist_table.py REPO"""

import re
import sys
from pathlib import Path

repo = Path(sys.argv[1])
page = (repo / "docs" / "vci.md").read_text()
section = page.split("## Checklist coverage", 1)
if len(section) != 2:
    sys.exit("docs/vci.md has no section \"## Checklist coverage\"")
rows = [line for line in section[1].split("\n## ", 1)[0].splitlines()
        if re.match(r"\| \d+ \|", line)]
items = [int(line.split("|")[1]) for line in rows]
problems = []
if items != list(range(1, 133)):
    problems.append(f"the rows are items {items[:3]}...{items[-3:]} ({len(items)}), not 1..132")
defined: dict[str, set[str]] = {}
for row in rows:
    item = row.split("|")[1].strip()
    named = re.findall(r"`([\w.]+\.cpp):(\w+)\.(\w+)`", row)
    if not named and "not testable" not in row:
        problems.append(f"item {item} names no test")
    for file, suite, test in named:
        if file not in defined:
            path = repo / "tests" / "system" / file
            defined[file] = set(re.findall(r"TEST(?:_F)?\(\s*(\w+),\s*(\w+)\)", path.read_text())
                                if path.exists() else [])
        if (suite, test) not in {tuple(t) for t in defined[file]}:
            problems.append(f"item {item}: {file} defines no {suite}.{test}")
for p in problems:
    print(p)
print(f"{len(rows)} rows, {sum(len(v) for v in defined.values())} tests in "
      f"{len(defined)} files looked at; {len(problems)} problems")
sys.exit(1 if problems else 0)
