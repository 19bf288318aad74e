"""docs/dotnet.md's "Checklist coverage" table against the NUnit tests: a row for every item
1..48 of the .NET digest's checklist, in order, each naming a test (File.cs:Class.Method) that
tests/dotnet/File.cs defines as a [Test] method of that class.

Usage: dotnet_checklist_table.py REPO"""

import re
import sys
from pathlib import Path

from checklist_table import checklist_rows, finish

repo = Path(sys.argv[1])
rows, problems = checklist_rows(repo, "dotnet.md", 48)
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
finish(problems, f"{len(rows)} rows")
