"""``--results``: a benchmark writes what it printed into its own block of
``benchmarks/RESULTS.md``, so that the measured tables the docs cite come from the scripts,
not from copies. Shared by the benchmark scripts (``adaptor.py``, ``corpus.py``,
``oscillator_bank.py``, ``batch.py``, ``import_time.py``, ``streaming.py``, ``peers.py``,
``walk_push.py``, ``walk_frequency.py``, ``compile.py``).

A block lies between ``<!-- results: NAME -->`` and ``<!-- /results: NAME -->`` (NAME the
script's stem); a run with ``--results`` replaces it with the command line, the date, the
machine's CPU count and load, and every line the run printed. A RESULTS.md without the block
gets it appended under a heading of its own."""

from __future__ import annotations

import contextlib
import datetime
import io
import os
import re
import shlex
import sys
from collections.abc import Iterator
from pathlib import Path

RESULTS = Path(__file__).with_name("RESULTS.md")


def block(name: str) -> re.Pattern[str]:
    """The block of ``name`` in RESULTS.md: its markers and what lies between."""
    return re.compile(rf"(<!-- results: {re.escape(name)} -->\n)(.*?)(<!-- /results: "
                      rf"{re.escape(name)} -->)", re.DOTALL)


def replace(text: str, name: str, body: str) -> str:
    """``text`` (RESULTS.md) with block ``name`` holding ``body``; appended if absent."""
    body = body.rstrip("\n") + "\n"
    pattern = block(name)
    if pattern.search(text):
        return pattern.sub(lambda m: m.group(1) + body + m.group(3), text, count=1)
    return (text.rstrip("\n") + f"\n\n## {name}\n\n<!-- results: {name} -->\n{body}"
            f"<!-- /results: {name} -->\n")


def header(argv: list[str]) -> str:
    """Which command produced a block, when and where."""
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"Written by `python benchmarks/{Path(argv[0]).name} {shlex.join(argv[1:])}` on "
            f"{datetime.date.today().isoformat()} ({os.cpu_count()} CPUs, load {load:.1f} at the "
            "end):\n\n")


def markdown(printed: str) -> str:
    """What a benchmark printed as Markdown: its table rows (lines starting with ``|``) as a
    table, every other run of lines in a ``text`` block (aligned columns stay aligned)."""
    runs: list[tuple[bool, list[str]]] = []
    for line in printed.rstrip("\n").splitlines():
        table = line.startswith("|")
        if runs and runs[-1][0] == table:
            runs[-1][1].append(line)
        else:
            runs.append((table, [line]))
    return "\n\n".join("\n".join(lines) if table else "```text\n" + "\n".join(lines) + "\n```"
                       for table, lines in runs) + "\n"


class _Tee(io.TextIOBase):
    """Writes to the real stdout and keeps a copy."""

    def __init__(self, out: io.TextIOBase) -> None:
        self.out, self.copy = out, io.StringIO()

    def write(self, s: str) -> int:
        self.copy.write(s)
        return self.out.write(s)

    def flush(self) -> None:
        self.out.flush()


@contextlib.contextmanager
def recording(name: str, enabled: bool, path: Path = RESULTS) -> Iterator[None]:
    """Within the block, what is printed is also kept; on a normal exit with ``enabled`` it
    replaces block ``name`` of ``path``."""
    if not enabled:
        yield
        return
    tee = _Tee(sys.stdout)  # type: ignore[arg-type]
    with contextlib.redirect_stdout(tee):
        yield
    body = markdown(tee.copy.getvalue())
    path.write_text(replace(path.read_text(), name, header(sys.argv) + body))
    print(f"{path.name}: block {name!r} written")


def add_flag(parser) -> None:
    """The ``--results`` option of a benchmark's argument parser."""
    parser.add_argument("--results", action="store_true",
                        help=f"also write what is printed into {RESULTS.name}'s block of "
                             "this benchmark")
