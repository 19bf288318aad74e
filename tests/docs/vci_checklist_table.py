"""docs/vci.md's "Checklist coverage" table against the tests: a row for every item 1..132 of
the VCI digest's checklist, in order, each naming at least one test through an API, and every
test it names (file:Suite.Test) defined in that file under tests/system/. A row may instead say
why an item has no test ("not testable: ...").

Usage: vci_checklist_table.py REPO"""

import re
import sys
from pathlib import Path

from checklist_table import checklist_rows, finish

repo = Path(sys.argv[1])
rows, problems = checklist_rows(repo, "vci.md", 132)
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
finish(problems, f"{len(rows)} rows, {sum(len(v) for v in defined.values())} tests in "
       f"{len(defined)} files looked at")
