"""README.md is a short front page whose quick start works as written.

* at most 300 lines (the manual is the guide in docs/);
* every ``acmm``/``qpp`` command of its quick start is a command the CLI knows (``--help`` exits
  0) and every config it names, with its overrides, validates;
* ``make run``, the quick start's first line, runs ``acmm simulate`` and prints the figure the
  README says to open, and ``source .venv/bin/activate`` names the venv's activation script;
* (slow) the quick start runs as written in an empty folder — ``make run``'s command first, then
  every command after it, with the venv's ``acmm`` and ``qpp`` — and every run folder and
  figure it names exists afterwards.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO, invoke

README = REPO / "README.md"
MAX_LINES = 300


def _text() -> str:
    return README.read_text(encoding="utf-8")


def quick_start(text: str | None = None) -> tuple[list[str], str]:
    """The command lines of the README's quick-start code block (comments dropped) and the
    section's whole text."""
    text = _text() if text is None else text
    m = re.search(r"^## Quick start\n(?P<body>.*?)(?=^## )", text, re.S | re.M)
    assert m, "README.md has no '## Quick start' section"
    block = re.search(r"```(?:sh|console|bash)?\n(?P<code>.*?)```", m["body"], re.S)
    assert block, "the quick start has no code block"
    lines = [line.split("#", 1)[0].strip() for line in block["code"].splitlines()]
    return [line for line in lines if line], m["body"]


def test_readme_is_at_most_300_lines():
    assert len(_text().splitlines()) <= MAX_LINES


def test_quick_start_parser_finds_the_commands():
    commands, _ = quick_start("## Quick start\n\n```sh\nmake run   # x\nacmm design mb3  # y\n```\n\n## Next\n")
    assert commands == ["make run", "acmm design mb3"]


def _app(program: str):
    if program == "acmm":
        from acmm.cli.app import app
    else:
        from qpp.cli import app
    return app


def test_every_quick_start_command_parses_and_its_config_validates(tmp_runs):
    """Each acmm/qpp line: the command exists (``--help``), and the CONFIG and ``KEY=VALUE``
    words it gives validate (``acmm validate`` / ``qpp validate``), without running it."""
    commands, _ = quick_start()
    tools = [shlex.split(c) for c in commands if c.split()[0] in ("acmm", "qpp")]
    assert len(tools) >= 2
    for words in tools:
        program, command, args = words[0], words[1], words[2:]
        helped = invoke(_app(program), command, "--help")
        assert helped.exit_code == 0, f"{' '.join(words)}: --help exits {helped.exit_code}: {helped.output}"
        positional = [a for a in args if not a.startswith("-")]
        if command in ("design", "simulate", "tea", "linearize", "certify", "sweep", "validate"):
            checked = invoke(_app(program), "validate", *positional)
            assert checked.exit_code == 0, f"{' '.join(words)}: {checked.output}"
    assert list(tmp_runs.iterdir()) == []          # nothing was run


def _make_run_recipe() -> list[str]:
    recipe, inside = [], False
    for line in (REPO / "Makefile").read_text(encoding="utf-8").splitlines():
        if re.match(r"^run:", line):
            inside = True
        elif inside and line.startswith("\t"):
            recipe.append(line.strip())
        elif inside:
            break
    return recipe


def test_make_run_simulates_and_names_the_figure_the_readme_opens():
    commands, section = quick_start()
    assert commands[0] == "make run" and "source .venv/bin/activate" in commands
    recipe = " ".join(_make_run_recipe())
    assert "acmm simulate" in recipe and "source $(VENV)/bin/activate" in recipe
    figure = re.search(r"open the stair-case's summary, `(runs/staircase/[\w.]+\.png)`", section)
    assert figure and figure[1] in recipe          # make run prints the figure the README opens
    assert (Path(sys.prefix) / "bin" / "activate").is_file()


@pytest.mark.slow
def test_quick_start_runs_as_written_in_an_empty_folder(tmp_path):
    """The quick start, in an empty folder: ``make run``'s simulation (the packaged stair-case),
    then every acmm/qpp line as written, with the venv's scripts on PATH (what ``source
    .venv/bin/activate`` gives). Each exits 0 and every run folder and figure the section names
    exists."""
    commands, section = quick_start()
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])),
           "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1"}
    recipe = [line for line in _make_run_recipe() if "acmm simulate" in line]
    assert len(recipe) == 1
    runs = [["acmm", *recipe[0].split("/acmm", 1)[1].split()]]          # `$(BIN)/acmm simulate`
    assert runs[0][:2] == ["acmm", "simulate"]
    runs += [shlex.split(c) for c in commands if c.split()[0] in ("acmm", "qpp")]
    for words in runs:
        out = subprocess.run(words, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, f"{' '.join(words)}: exit {out.returncode}\n{out.stderr[-2000:]}"
    named = set(re.findall(r"\bruns/[\w./]+", section))
    assert "runs/staircase/sim_summary.png" in named
    assert sorted(p for p in named if not (tmp_path / p.rstrip("/.")).exists()) == []
