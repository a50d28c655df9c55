"""Reading a run folder's streamed files (trajectory.csv, timing.csv,
events.jsonl, scan.csv, encounters.csv, diagnostics.csv) as the Rust
readers do: a torn last row of a cut run (a world killed while writing it:
every writer ends each row with a newline) is left out and reported, any
other bad row is an error naming the file and the line."""

import json
from pathlib import Path
from typing import List, NamedTuple, Optional


class Rows(NamedTuple):
    """What :func:`load_rows` gives back."""

    rows: list
    """The rows: for a CSV file one dict per row (column name -> text), for
    a JSONL file one parsed object per line."""
    cut: Optional[str]
    """``None`` for a file that ends with a whole row; for a cut one,
    ``"FILE:LINE: the run was cut: ..."`` (that line was left out)."""


def load_rows(path) -> Rows:
    """Reads one of a run folder's streamed files (``.csv`` or ``.jsonl``).

    A last line without its newline was torn by a killed writer: it is left
    out and named in :attr:`Rows.cut`. A malformed line elsewhere (a CSV row
    with another number of cells than the header, a line that is not JSON)
    raises ``ValueError("FILE:LINE: reason")``.
    """
    path = Path(path)
    data = path.read_bytes()
    cut = None
    if data and not data.endswith(b"\n"):
        keep = data.rfind(b"\n") + 1
        line = data[:keep].count(b"\n") + 1
        data = data[:keep]
        cut = (
            f"{path}:{line}: the run was cut: its last line is torn (the writer "
            f"was killed while writing it); read up to line {line - 1}"
        )
    lines: List[str] = data.decode("utf-8").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    rows = []
    if path.suffix == ".jsonl":
        for n, text in enumerate(lines, 1):
            if not text.strip():
                continue
            try:
                rows.append(json.loads(text))
            except ValueError as e:
                raise ValueError(f"{path}:{n}: {e}") from None
        return Rows(rows, cut)
    if not lines:
        return Rows(rows, cut)
    header = [c.strip() for c in lines[0].rstrip("\r").split(",")]
    for n, text in enumerate(lines[1:], 2):
        text = text.rstrip("\r")
        if not text.strip():
            continue
        cells = [c.strip() for c in text.split(",")]
        if len(cells) != len(header):
            raise ValueError(
                f"{path}:{n}: {len(cells)} fields, the header has {len(header)}"
            )
        rows.append(dict(zip(header, cells)))
    return Rows(rows, cut)
