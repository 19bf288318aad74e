"""What the checks of the docs' "Checklist coverage" tables share (dotnet_checklist_table.py,
vci_checklist_table.py): the rows of a page's table, and the verdict."""

import re
import sys
from pathlib import Path


def checklist_rows(repo: Path, page_name: str, last: int) -> tuple[list[str], list[str]]:
    """The rows of docs/PAGE_NAME's "Checklist coverage" table (the program ends if the page
    has no such section), and a problem if they are not the items 1..LAST in order."""
    page = (repo / "docs" / page_name).read_text()
    section = page.split("## Checklist coverage", 1)
    if len(section) != 2:
        sys.exit(f"docs/{page_name} has no section \"## Checklist coverage\"")
    rows = [line for line in section[1].split("\n## ", 1)[0].splitlines()
            if re.match(r"\| \d+ \|", line)]
    items = [int(line.split("|")[1]) for line in rows]
    problems = []
    if items != list(range(1, last + 1)):
        problems.append(f"the rows are items {items[:3]}...{items[-3:]} ({len(items)}), "
                        f"not 1..{last}")
    return rows, problems


def finish(problems: list[str], summary: str) -> None:
    """Prints the problems and the summary; ends the program, failing if there are problems."""
    for p in problems:
        print(p)
    print(f"{summary}; {len(problems)} problems")
    sys.exit(1 if problems else 0)
