#!/usr/bin/env python
"""The generated blocks of README.md and the guide (docs/): found, checked and rewritten.

Every number the README or a page of the guide quotes about a packaged config sits in a block
``<!-- generated:NAME -->`` … ``<!-- /generated:NAME -->`` whose text the report computes
(:mod:`acmm.report.pages`, from a fresh run into a temporary results root, the numbers
written by :mod:`acmm.report.numbers` as in the HTML report).  This script finds the blocks in
README.md and ``docs/**/*.md`` (each exactly once across them), compares and replaces their text
(``tests/test_readme_numbers.py`` checks them against a fresh run).

    python scripts/readme_numbers.py            # rewrite the blocks where they live (make readme)
    python scripts/readme_numbers.py --check    # exit 1 and name the blocks that differ
"""
from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

from acmm.report.pages import BLOCKS, run_stages  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
README = REPO / "README.md"
_BLOCK_RE = re.compile(r"<!-- generated:(?P<name>[a-z0-9_]+) -->\n(?P<body>.*?)<!-- /generated:(?P=name) -->",
                       re.S)


def use_this_trees_configs() -> None:
    """Make the packaged configs (``acmm.configs``) this tree's ``configs/`` folder.

    An editable install made from another checkout maps ``acmm.configs`` to that checkout's
    folder, whatever ``PYTHONPATH`` says; the README describes this tree's configs.
    """
    here = (REPO / "configs").resolve()
    mod = sys.modules.get("acmm.configs")
    if mod is not None and [Path(p).resolve() for p in mod.__path__] == [here]:
        return
    spec = importlib.util.spec_from_file_location("acmm.configs", here / "__init__.py",
                                                  submodule_search_locations=[str(here)])
    mod = importlib.util.module_from_spec(spec)
    sys.modules["acmm.configs"] = mod
    spec.loader.exec_module(mod)


def documents() -> list[Path]:
    """The files that may hold generated blocks: README.md first, then every ``docs/**/*.md``.

    Returns
    -------
    list of pathlib.Path
        The documents, the guide's pages in path order.
    """
    return [README] + sorted((REPO / "docs").rglob("*.md"))


def read_texts(paths: list[Path] | None = None) -> dict[Path, str]:
    """The texts of the documents.

    Parameters
    ----------
    paths : list of pathlib.Path, optional
        The documents (default: :func:`documents`).

    Returns
    -------
    dict
        Path → its text.
    """
    return {p: p.read_text(encoding="utf-8") for p in (documents() if paths is None else paths)}


def _name(path: Path) -> str:
    return path.relative_to(REPO).as_posix() if path.is_relative_to(REPO) else str(path)


def locate_blocks(texts: dict[Path, str]) -> dict[str, tuple[Path, str]]:
    """Where each generated block lives among the documents, and its text.

    Parameters
    ----------
    texts : dict
        Path → text (:func:`read_texts`).

    Returns
    -------
    dict
        Block name → (the document holding it, the text between its markers).

    Raises
    ------
    ValueError
        A block appears twice, in one document or in two.
    """
    found: dict[str, tuple[Path, str]] = {}
    for path, text in texts.items():
        for m in _BLOCK_RE.finditer(text):
            if m["name"] in found:
                first = found[m["name"]][0]
                raise ValueError(f"{_name(path)}: block {m['name']!r} appears twice" if first == path else
                                 f"block {m['name']!r} appears twice: in {_name(first)} and {_name(path)}")
            found[m["name"]] = (path, m["body"])
    return found


def replace_blocks(texts: dict[Path, str], blocks: dict[str, str]) -> dict[Path, str]:
    """The documents with each generated block's body replaced by ``blocks[name]``.

    Parameters
    ----------
    texts : dict
        Path → text of the documents.
    blocks : dict
        Block name → new text.

    Returns
    -------
    dict
        Path → the new text (every document of ``texts``).

    Raises
    ------
    ValueError
        A block of ``blocks`` has no markers in any document, or a block appears twice.
    """
    missing = sorted(set(blocks) - set(locate_blocks(texts)))
    if missing:
        raise ValueError(f"no markers for {missing} in README.md or docs/")

    def sub(m):
        return f"<!-- generated:{m['name']} -->\n{blocks.get(m['name'], m['body'])}<!-- /generated:{m['name']} -->"
    return {path: _BLOCK_RE.sub(sub, text) for path, text in texts.items()}


def check(texts: dict[Path, str], blocks: dict[str, str]) -> list[str]:
    """The blocks that differ from ``blocks`` (or are missing), with the document and the first
    differing line.

    Parameters
    ----------
    texts : dict
        Path → text of the documents.
    blocks : dict
        Block name → expected text.

    Returns
    -------
    list of str
        One line per wrong block; empty when the documents hold every block once.
    """
    try:
        have = locate_blocks(texts)
    except ValueError as exc:
        return [str(exc)]
    bad = []
    for name, want in blocks.items():
        if name not in have:
            bad.append(f"{name}: no <!-- generated:{name} --> block in README.md or docs/")
        elif have[name][1] != want:
            path, got = have[name]
            line = next((f"{_name(path)} {a!r} != computed {b!r}" for a, b in
                         zip(got.splitlines(), want.splitlines()) if a != b), f"{_name(path)}: different length")
            bad.append(f"{name}: {line}")
    return bad


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or ``--check``) the generated blocks of README.md and docs/ from a fresh run.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments.

    Returns
    -------
    int
        0, or 1 when ``--check`` found a wrong block.
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 when a block differs")
    ap.add_argument("--workers", type=int, default=None, help="sweep workers (default: min(2, CPUs))")
    args = ap.parse_args(argv)
    texts = read_texts()
    locate_blocks(texts)                # a block twice: say so before the runs
    use_this_trees_configs()
    with tempfile.TemporaryDirectory(prefix="readme-numbers-") as tmp:     # the stages run here, never in runs/
        r = run_stages(Path(tmp), args.workers)
        blocks = {name: block(r) for name, block in BLOCKS.items()}
    if args.check:
        bad = check(texts, blocks)
        print("\n".join(bad) if bad else f"{len(blocks)} generated blocks: all as computed")
        return 1 if bad else 0
    new = replace_blocks(texts, blocks)
    changed = [path for path in texts if new[path] != texts[path]]
    for path in changed:
        path.write_text(new[path], encoding="utf-8")
    print(f"{len(blocks)} generated blocks; rewritten: {', '.join(_name(p) for p in changed) or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
