"""What every ``acmm`` command shares: the kinds of config ``acmm`` reads (:data:`CONFIGS`), the
``--figures/--no-figures`` option (:data:`FiguresOpt`) and the decorator :data:`acmm_command`
(:func:`acmm_qpp.cli.plumbing.user_errors`: one ``error:`` line, with the hint the error was raised
with, and the ``note:`` lines numba's cache leaves after a run)."""
from __future__ import annotations

import functools
import sys

import typer

from acmm import PACKAGED_CONFIGS
from acmm_qpp.cli.plumbing import ConfigKinds, user_errors
from qpp import CONFIG_SECTIONS as QPP_SECTIONS

#: The packaged configs and the three kinds of config ``acmm`` reads (``acmm validate``, ``acmm
#: schema``): a sweep (a ``sweep`` section, or the resolved form's ``sweep_file``), a qpp config
#: (checked by ``acmm validate`` too), else an acmm run config.
CONFIGS = ConfigKinds(PACKAGED_CONFIGS, (("sweep", ("sweep", "sweep_file")), ("qpp", QPP_SECTIONS), ("acmm", ())),
                      "A config path is relative to the working directory; a bare name that is no file there "
                      "(mb3, mb3.yaml) is a packaged config. A config a config names (sweep.base, schedule.to) is "
                      "looked up beside the naming file, then in the working directory, then among the packaged "
                      "configs.")


#: ``--figures/--no-figures`` of the acmm commands that draw figures
FiguresOpt = typer.Option(None, "--figures/--no-figures", help="write figures (default: output.figures)")


def _compiled_cache_notes() -> list[str]:
    """A line for each reason numba could not save a kernel it compiled in this run (none when
    nothing was compiled: the cache module was not even imported)."""
    cache = sys.modules.get("acmm.model.compiled_cache")       # (not imported: nothing was compiled)
    return cache.write_error_notes() if cache is not None else []


#: The decorator of an ``acmm`` command: :func:`acmm_qpp.cli.plumbing.user_errors` with numba's cache notes.
acmm_command = functools.partial(user_errors, notes=_compiled_cache_notes)
