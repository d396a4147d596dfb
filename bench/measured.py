"""The measured part of a page of docs/: a benchmark writes its tables between its markers,
`<!-- MEASURED (bench/SCRIPT.py) -->` and `<!-- /MEASURED -->`, and leaves the rest of the page."""

from pathlib import Path

END = "<!-- /MEASURED -->"


def publish(page: Path, script: str, text: str):
    begin = f"<!-- MEASURED ({script}) -->"
    head, rest = page.read_text().split(begin, 1)
    _, tail = rest.split(END, 1)
    page.write_text(f"{head}{begin}\n\n{text}\n{END}{tail}")
    print(f"written: {page}")
