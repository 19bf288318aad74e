"""docs/dotnet.md's "Checklist coverage" table against the NUnit tests: a row for every item
1..48 of the .NET digest's checklist, in order, each naming a test (File.cs:Class.Method) that
tests/dotnet/File.cs defines as a [Test] method of that class.

Usage: dotnet_checklist_table.py REPO"""

import re
import sys
from pathlib import Path

repo = Path(sys.argv[1])
page = (repo / "docs" / "dotnet.md").read_text()
section = page.split("## Checklist coverage", 1)
if len(section) != 2:
    sys.exit("docs/dotnet.md has no section \"## Checklist coverage\"")
rows = [line for line in section[1].split("\n## ", 1)[0].splitlines() if re.match(r"\| \d+ \|", line)]
items = [int(line.split("|")[1]) for line in rows]
problems = []
if items != list(range(1, 49)):
    problems.append(f"the rows are items {items[:3]}...{items[-3:]} ({len(items)}), not 1..48")
for row in rows:
    item = row.split("|")[1].strip()
    named = re.findall(r"`(\w+\.cs):(\w+)\.(\w+)`", row)
    if not named:
        problems.append(f"item {item} names no test")
    for file, fixture, test in named:
        path = repo / "tests" / "dotnet" / file
        text = path.read_text() if path.exists() else ""
        if not re.search(rf"public class {fixture}\b", text):
            problems.append(f"item {item}: {file} has no class {fixture}")
        if not re.search(rf"\[Test\]\s*public void {test}\(", text):
            problems.append(f"item {item}: {file} has no [Test] {test}")
for p in problems:
    print(p)
print(f"{len(rows)} rows; {len(problems)} problems")
sys.exit(1 if problems else 0)
