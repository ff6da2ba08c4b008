"""Shared CLI plumbing: one clear message and a documented exit code for every user error
(:mod:`acmm_qpp.errors` lists the codes): an :class:`acmm_qpp.errors.AcmmError` or another
user-facing failure (:func:`acmm_qpp.errors.plain_failure`, shared with the report's failed
sections), an interrupt that Python wrapped in another exception, click's usage errors, the
numerical warnings of a run and a closed standard output each become one line."""
from __future__ import annotations

import contextlib
import functools
import os
import re
import sys
import threading
import warnings
from importlib import resources
from typing import NamedTuple

import typer
from typer.core import TyperCommand, TyperGroup

try:
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover (typer < 0.20 uses click itself)
    from click import exceptions as click_exceptions
try:
    from typer._click.utils import _detect_program_name
except ImportError:  # pragma: no cover
    from click.utils import _detect_program_name

from acmm_qpp.errors import (EXIT_INPUT, EXIT_INTERRUPTED, EXIT_USAGE, EXIT_VERDICT, AcmmError, ConfigError,
                             plain_failure, with_hint)
from acmm_qpp.plot_style import files_only_backend
from acmm_qpp.signals import ignore_interrupts, terminate_like_ctrl_c


def fail(message: str, code: int = EXIT_INPUT) -> None:
    """Print ``error: message`` on stderr (one line) and exit with ``code`` (no traceback).

    Parameters
    ----------
    message : str
        The error; whitespace runs are joined to one space and it is cut to :data:`MAX_MESSAGE`
        characters.
    code : int, optional
        Exit code (:mod:`acmm_qpp.errors`; default ``EXIT_INPUT``, 2).

    Raises
    ------
    typer.Exit
        Always, with ``code``.
    """
    message = " ".join(str(message).split())
    if len(message) > MAX_MESSAGE:        # e.g. a megabyte-long key echoed in a field name
        message = message[:MAX_MESSAGE - 20] + " … (truncated)"
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


MAX_MESSAGE = 600


#: exit code when the reader of standard output closed it (128 + SIGPIPE, as a C tool killed by it)
EXIT_PIPE_CLOSED = 141


def quiet_stdout() -> None:
    """Point stdout at /dev/null, so that flushing it at exit raises nothing more."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())


def user_errors(fn, notes=None):
    """Decorator for typer commands: turn :class:`AcmmError` into one line on stderr (with the
    hint it was raised with, :func:`acmm_qpp.errors.with_hint`) and the error's ``exit_code``.

    numpy/scipy warnings are captured: a refused run prints only its error line; a successful
    one a single ``note:`` line counting them.  Numerical exceptions outside the hierarchy
    (``LinAlgError``, ``FloatingPointError``…) exit 3, OS errors 4, a ``RecursionError`` 2, all
    on one line.

    Parameters
    ----------
    fn : callable
        The command function.
    notes : callable, optional
        ``notes() -> list of str``: the product's ``note:`` lines after a successful run.

    Returns
    -------
    callable
        The wrapped command (same name, docstring and signature, so typer sees the same options).
    """

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")      # each distinct warning once (a hot loop stays cheap)
            try:
                out = fn(*args, **kwargs)
            except AcmmError as exc:
                fail(with_hint(exc), exc.exit_code)
            except KeyboardInterrupt as exc:
                _interrupted(exc)
            except BrokenPipeError:     # the reader of stdout went away (`| head`): not an I/O failure
                quiet_stdout()         # of the results, which the stage wrote before printing
                sys.exit(EXIT_PIPE_CLOSED)
            except Exception as exc:  # noqa: BLE001 (re-raised unless a known kind of failure)
                cause, seen = exc, set()     # Python may wrap a Ctrl-C (in a class body: RuntimeError)
                while cause is not None and id(cause) not in seen:
                    if isinstance(cause, KeyboardInterrupt):
                        _interrupted(cause)
                    seen.add(id(cause))
                    cause = cause.__cause__ or cause.__context__
                plain = plain_failure(exc)
                if plain is None:
                    raise
                fail(*plain)
        caught = [w for w in caught if not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning))]
        if caught:                  # one summary line for the numerical warnings, never raw
            typer.echo(f"note: {len(caught)} distinct numerical warning(s) during the run; first: "
                       f"{caught[0].category.__name__}: {' '.join(str(caught[0].message).split())}", err=True)
        for line in notes() if notes is not None else []:
            typer.echo(f"note: {line}", err=True)
        return out

    return wrapper


# ---------------------------------------------------------------------------------------------
# command-line conventions (issue 14): exit codes of click errors, --version, overrides, --strict
# ---------------------------------------------------------------------------------------------
def overrides_arg(example: str):
    """The positional ``KEY=VALUE`` overrides after CONFIG (see :mod:`acmm_qpp.configio`), their
    help naming ``example``, an override of a key the command reads.

    Parameters
    ----------
    example : str
        One or two overrides of keys the command reads, e.g. ``"a.b=0.6"``.

    Returns
    -------
    typer.models.ArgumentInfo
        The argument.
    """
    return typer.Argument(None, metavar="KEY=VALUE",
                          help=f"overrides of config values, dotted, e.g. {example} "
                               "(validated like the file; ~key removes one)",
                          show_default=False)


class ConfigKinds(NamedTuple):
    """A product's packaged configs and the kinds of config it tells apart by their top-level keys
    (the base knows no kind: each product gives its own).

    Parameters
    ----------
    package : str
        The data package of the product's packaged configs.
    kinds : tuple
        ``(kind, top-level keys)`` pairs: a config is of the first kind one of whose keys it has;
        a pair with no keys takes any config.
    path_rule : str, optional
        How a command finds a config it is given, as the product's help states it.
    """

    package: str
    kinds: tuple
    path_rule: str = ""

    def kind_of(self, data: object) -> str:
        """The kind of a parsed config (empty when none of :attr:`kinds` takes it).

        Parameters
        ----------
        data : object
            Parsed YAML (a mapping; anything else has no keys).

        Returns
        -------
        str
            The kind.
        """
        top = set(data) if isinstance(data, dict) else set()
        return next((kind for kind, keys in self.kinds if not keys or top & set(keys)), "")

    def packaged(self, wanted: tuple) -> list[str]:
        """Names of the packaged configs of the ``wanted`` kinds, read from the folder when called
        (a help screen lists what is installed), each kind read from the file's top-level keys
        without parsing its YAML.

        Parameters
        ----------
        wanted : tuple of str
            Kinds of :attr:`kinds`.

        Returns
        -------
        list of str
            Sorted names without ``.yaml``; empty when the folder cannot be read.
        """
        try:
            files = sorted(resources.files(self.package).iterdir(), key=lambda p: p.name)
            tops = {f.name[:-5]: re.findall(r"^([A-Za-z_]\w*)\s*:", f.read_text(encoding="utf-8"), flags=re.M)
                    for f in files if f.name.endswith(".yaml")}
        except (OSError, ModuleNotFoundError):  # pragma: no cover (a broken installation)
            return []
        return [name for name, top in tops.items() if self.kind_of(dict.fromkeys(top)) in wanted]


def _write_epilog(formatter, examples=(), configs: ConfigKinds | None = None, kinds: tuple = (),
                  command: bool = True) -> None:
    """Write ``Examples:`` and the command lines ``examples`` (one a line, unwrapped) and, for
    ``kinds``, the packaged configs of those kinds (:meth:`ConfigKinds.packaged`, listed from the
    folder now: a help screen lists what is installed); a command's help (``command``, else the
    app's) also names the kinds and the rule by which config paths are found (:attr:`ConfigKinds.path_rule`)."""
    if examples:
        formatter.write_paragraph()
        formatter.write_text("Examples:")
        with formatter.indentation():
            for line in examples:
                formatter.write(f"{'':>{formatter.current_indent}}{line}\n")
    if kinds:
        names = configs.packaged(tuple(kinds))
        formatter.write_paragraph()
        if not command:
            formatter.write_text("Packaged configs (give the name instead of a file): " + ", ".join(names))
            return
        formatter.write_text(f"Packaged configs ({', '.join(kinds)}; give the name instead of a file): "
                             + (", ".join(names) if names else "none installed"))
        formatter.write_paragraph()
        formatter.write_text(configs.path_rule)


def help_command(examples: list, kinds: tuple = (), configs: ConfigKinds | None = None):
    """A typer command class whose help ends with ``examples`` (one command line each, kept as
    written) and, for ``kinds``, the packaged configs of those kinds listed from the folder at
    help time and the product's rule by which config paths are found (:class:`ConfigKinds`).

    Parameters
    ----------
    examples : list of str
        Command lines, each shown on a line of its own under ``Examples:``.
    kinds : tuple of str, optional
        Config kinds the command reads (:meth:`ConfigKinds.packaged`); empty: no config list.
    configs : ConfigKinds, optional
        The product's packaged configs and kinds, listed for ``kinds``.

    Returns
    -------
    type
        A subclass of ``typer.core.TyperCommand`` for ``app.command(cls=...)``.
    """
    class WithExamples(TyperCommand):
        """A command whose help ends with its examples and the packaged configs it can read."""

        def format_epilog(self, ctx, formatter) -> None:
            """Write the examples (unwrapped), the packaged configs and the path rule, then the
            command's own epilog."""
            _write_epilog(formatter, examples, configs, kinds)
            super().format_epilog(ctx, formatter)

    return WithExamples


StrictOpt = typer.Option(False, "--strict", help="exit 1 when the run finishes with a failing verdict "
                                                 "(for CI)")
#: ``--out`` of ``acmm plot`` and ``qpp plot`` (:func:`redraw_command`)
OutOpt = typer.Option(None, "--out", help="folder of the figures (default: the results file's folder)")


def _interrupted(exc: BaseException) -> None:
    """Report the ``KeyboardInterrupt`` (or ``typer.Abort``) ``exc`` caught: Ctrl-C ("interrupted",
    exit 130) or SIGTERM/SIGHUP (:class:`acmm_qpp.errors.Terminated`: "terminated by signal N",
    exit 128 + N) on one line, and exit."""
    code = getattr(exc, "exit_code", None)
    if isinstance(code, int):
        typer.echo(f"terminated by signal {code - 128}", err=True)
        sys.exit(code)
    typer.echo("interrupted", err=True)
    sys.exit(EXIT_INTERRUPTED)


class ExitCodeGroup(TyperGroup):
    """The apps' click group: click's own errors get the documented exit codes, on one line.

    * a usage error (unknown option or command, missing argument, extra argument) → 64
      (``EXIT_USAGE``);
    * a bad *value* of an option or argument (``-j 0``, ``--kind foo``) → 2 (``EXIT_INPUT``, like a
      bad value in a config file);
    * Ctrl-C → 130; SIGTERM / SIGHUP → 143 / 129 (:func:`acmm_qpp.signals.terminate_like_ctrl_c`),
      also while click parses.
    """

    #: command lines shown under ``Examples:`` at the end of the app's help
    examples: tuple = ()
    #: config kinds whose packaged configs the app's help lists (:meth:`ConfigKinds.packaged`)
    config_kinds: tuple = ()
    #: the product's packaged configs and kinds (:class:`ConfigKinds`)
    configs: ConfigKinds | None = None

    def format_epilog(self, ctx, formatter) -> None:
        """Write the app's examples and packaged configs (listed from the folder), then its epilog.

        Parameters
        ----------
        ctx : click.Context
            The app's context.
        formatter : click.HelpFormatter
            The help being written.
        """
        _write_epilog(formatter, self.examples, self.configs, self.config_kinds, command=False)
        super().format_epilog(ctx, formatter)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        """Parse ``args`` and run the command, mapping click's errors to the exit codes.

        The steps of :meth:`click.Command.main` (shell completion, the context, the command), not
        typer's, which turns a Ctrl-C or SIGTERM while click parses into a silent exit 130.

        Parameters
        ----------
        args : list of str, optional
            Command-line arguments (default: ``sys.argv[1:]``).
        prog_name : str, optional
            Program name shown in usage lines.
        complete_var : str, optional
            Environment variable of shell completion.
        standalone_mode : bool, optional
            False: click's own behaviour (exceptions, an interrupt included, propagate; the
            return value or the exit code of ``typer.Exit`` is returned).
        **extra : dict
            Passed on to click.

        Returns
        -------
        object
            The command's return value, only when ``standalone_mode`` is False (otherwise the
            process exits).
        """
        args = sys.argv[1:] if args is None else list(args)
        prog_name = prog_name or _detect_program_name()
        self._main_shell_completion(extra, prog_name, complete_var)
        if not standalone_mode:
            return self._run(prog_name, args, extra)
        try:
            rv = self._run(prog_name, args, extra)
        except click_exceptions.NoArgsIsHelpError as exc:
            typer.echo(exc.ctx.get_help() if exc.ctx is not None else exc.format_message(), err=True)
            sys.exit(EXIT_USAGE)
        except click_exceptions.UsageError as exc:      # a bad value (not a missing one) is bad input
            msg = " ".join(exc.format_message().replace("Value error, ", "").split())
            where = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
            typer.echo(f"error: {msg}{where}", err=True)
            bad_value = (isinstance(exc, click_exceptions.BadParameter)
                         and not isinstance(exc, click_exceptions.MissingParameter))
            sys.exit(EXIT_INPUT if bad_value else EXIT_USAGE)
        except click_exceptions.ClickException as exc:
            typer.echo(f"error: {' '.join(exc.format_message().split())}", err=True)
            sys.exit(exc.exit_code)
        except (typer.Abort, KeyboardInterrupt, EOFError) as exc:
            _interrupted(exc)
        except BrokenPipeError:         # the help's reader went away (`acmm --help | head -1`)
            quiet_stdout()
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)

    def _run(self, prog_name: str, args: list, extra: dict):
        """The command's return value, or the exit code of a ``typer.Exit`` (``--help``, ...)."""
        try:
            with self.make_context(prog_name, args, **extra) as ctx:
                return self.invoke(ctx)
        except typer.Exit as exc:
            return exc.exit_code


#: the end of each app's help
EXIT_CODES = ("Exit codes: 0 success, 1 failing verdict with --strict, 2 bad input (config, override or option value), "
              "3 numerical failure, 4 output/I-O, 64 usage, 130 interrupted.")


def product_app(about: str, examples: tuple, configs: ConfigKinds, kinds: tuple) -> typer.Typer:
    """A product's typer app (an :class:`ExitCodeGroup`): help ``about``, then ``examples``, the
    packaged configs of ``kinds`` and :data:`EXIT_CODES`; an eager ``--version`` prints
    ``acmm-qpp <version>`` (exit 0).

    Parameters
    ----------
    about : str
        The app's one-line help.
    examples : tuple of str
        Command lines shown under ``Examples:`` (:attr:`ExitCodeGroup.examples`).
    configs : ConfigKinds
        The product's packaged configs and kinds.
    kinds : tuple of str
        Kinds whose packaged configs the help lists.

    Returns
    -------
    typer.Typer
        The app, with no commands yet.
    """
    def show(value: bool) -> None:
        if value:
            from importlib.metadata import PackageNotFoundError, version  # deferred: for --version only

            try:
                v = version("acmm-qpp")
            except PackageNotFoundError:  # pragma: no cover (source tree without install)
                v = "unknown (not installed)"
            typer.echo(f"acmm-qpp {v}")
            raise typer.Exit(0)

    group = type("ProductGroup", (ExitCodeGroup,), {"examples": examples, "config_kinds": kinds, "configs": configs})
    app = typer.Typer(add_completion=True, no_args_is_help=True, cls=group, rich_markup_mode=None, help=about,
                      epilog=EXIT_CODES)

    @app.callback()
    def _root(version: bool = typer.Option(False, "--version", callback=show, is_eager=True,
                                           help="print the version and exit")) -> None:
        """The app's own options."""

    return app


def redraw_command(redraw, target: str, out) -> None:
    """The body of ``acmm plot`` and ``qpp plot``: ``redraw(target, out)`` (the figures of stored
    results), then one line per figure written.

    Parameters
    ----------
    redraw : callable
        ``redraw(target, out)`` → list of the paths written.
    target : str
        The run folder or results file given.
    out : str or None
        ``--out``: the folder of the figures (None: each file's own).

    Raises
    ------
    acmm_qpp.errors.ConfigError
        An empty ``--out`` (exit 2).
    """
    if out is not None and not out.strip():
        raise ConfigError("--out: empty; give the folder of the figures")
    written = redraw(target, out)
    typer.echo(f"{target}: redrew {len(written)} figure file(s)")
    for p in written:
        typer.echo(f"  wrote {p}")


def strict_exit(strict: bool, failed: bool, why: str) -> None:
    """With ``--strict``, a failing verdict exits 1 (``EXIT_VERDICT``) after the output, with one line.

    Parameters
    ----------
    strict : bool
        The ``--strict`` option was given.
    failed : bool
        The run's verdict is failing.
    why : str
        The one-line reason printed (``strict: why``) on stderr.

    Raises
    ------
    typer.Exit
        With code 1 when ``strict`` and ``failed``.
    """
    if strict and failed:
        typer.echo(f"strict: {' '.join(why.split())}", err=True)
        raise typer.Exit(EXIT_VERDICT)


def run_app(app) -> None:
    """Run a typer ``app`` (the console entry points) and leave with its exit code: SIGTERM and
    SIGHUP unwind like Ctrl-C and only the first interrupt counts
    (:func:`acmm_qpp.signals.terminate_like_ctrl_c`), figures go to files only
    (:func:`acmm_qpp.plot_style.files_only_backend`).  From the moment the app has returned,
    SIGINT, SIGTERM and SIGHUP are ignored: the run is finished and written, and a Ctrl-C landing
    in the exit path gave a KeyboardInterrupt traceback with exit 0, or killed a finished run by
    the signal (a review).

    Parameters
    ----------
    app : typer.Typer
        The application.
    """
    terminate_like_ctrl_c(once=True)
    files_only_backend()
    try:
        try:
            app()
        except KeyboardInterrupt as exc:    # while typer built the command, before the group's main
            _interrupted(exc)
    except SystemExit:
        if threading.current_thread() is threading.main_thread():
            with contextlib.suppress(OSError, ValueError):
                ignore_interrupts()
        raise
