"""The ``bayesupdate`` command.

Each sub-command lives in its own module under ``bayesupdate/commands/`` and defines
``NAME`` (str), ``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``.
Modules there are discovered automatically, so a command is added by adding a file.

Exit codes: 0 success, 1 the run failed (e.g. did not converge, internal error), 2 user error
(bad input, bad value, unknown name) - always one line on stderr, never a traceback.
Set ``BAYESUPDATE_DEBUG=1`` to see the traceback of an internal error.
"""

import os

from bayesupdate.compute.blas import BLAS_THREAD_VARIABLES

# The linear algebra here is small (n <= ~1000, batches of such): BLAS threads only add contention,
# badly so on a 2-core machine (measured: a modal solve 5 ms single-threaded, 50 ms with two
# threads on a busy machine).  Set before numpy loads (compute.blas imports nothing); a user's
# own setting wins.
for _var in BLAS_THREAD_VARIABLES:
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import importlib  # noqa: E402
import pkgutil  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402

from bayesupdate import __version__, commands  # noqa: E402
from bayesupdate.errors import BayesUpdateError  # noqa: E402


class _OneLineParser(argparse.ArgumentParser):
    """argparse prints usage plus an error on two lines and exits 2; we want one line."""

    def error(self, message):
        raise BayesUpdateError(f"{self.prog}: {message} (see --help)")


def _command_modules():
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"bayesupdate.commands.{info.name}")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``bayesupdate`` parser: every command by name and help line; the arguments of
    ``command`` only (a run parses one command's; None: every command's, e.g. for the docs)."""
    parser = _OneLineParser(
        prog="bayesupdate",
        description="Probabilistic FE model updating: modal solve, modal identification, "
        "calibration with uncertainty, discovery of missing physics.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="Exit codes: 0 success, 1 failed run, 2 user error.",
    )
    parser.add_argument("--version", action="version", version=f"bayesupdate {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_OneLineParser)
    for module in _command_modules():
        p = sub.add_parser(
            module.NAME,
            help=module.HELP,
            description=getattr(module, "DESCRIPTION", module.HELP),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        if command is None or module.NAME == command:
            _add_arguments(p, module)
        p.set_defaults(_run=module.run)
    return parser


def _add_arguments(p, module) -> None:
    """The command's own arguments, then --no-cache and --quiet."""
    module.add_arguments(p)
    if module.NAME != "cache":
        p.add_argument(
            "--no-cache",
            action="store_true",
            help="neither read nor write the on-disk cache of reduced bases (see: cache)",
        )
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress on stderr (default: bars on a terminal, a line per phase else)",
    )


def _command_in(argv: list[str] | None) -> str | None:
    """The command a command line names: its first word that is not an option (the top level
    takes options without values only); None without one."""
    words = sys.argv[1:] if argv is None else argv
    return next((w for w in words if not w.startswith("-")), None)


def main(argv: list[str] | None = None) -> int:
    try:
        parser = build_parser(_command_in(argv))
        args = parser.parse_args(argv)
        if getattr(args, "_run", None) is None:
            parser.print_help()
            return 2
        return _run(args)
    except BayesUpdateError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of stdout left (``... --json | head``): no fault
        _quiet_stdout()
        return 1
    except MemoryError as exc:
        # a size the user asked for (starts, walkers, particles) that no memory holds
        print(
            f"error: not enough memory for this run ({exc}); ask for fewer starts, walkers, "
            "particles, modes or lines",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # an internal fault: one line unless debugging
        if os.environ.get("BAYESUPDATE_DEBUG"):
            raise
        print(
            f"internal error: {type(exc).__name__}: {exc} "
            "(set BAYESUPDATE_DEBUG=1 for a traceback)",
            file=sys.stderr,
        )
        return 1


def _quiet_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's final flush of what is left
    for a closed pipe raises no second BrokenPipeError (Python's documented remedy, ``signal``
    module notes on SIGPIPE)."""
    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _run(args) -> int:
    """The command, its long phases shown on stderr (``compute.progress``: bars on a terminal,
    a line per phase otherwise, nothing with ``--quiet``), with ``--no-cache`` in force for its
    duration (``compute.cache`` reads the environment; restored after, so an in-process caller
    keeps its own)."""
    from bayesupdate.compute.progress import mode_for, reporting

    with reporting(mode_for(getattr(args, "quiet", False))), plain_warnings():
        if not getattr(args, "no_cache", False):
            return int(args._run(args) or 0)
        return _without_cache(args)


@contextlib.contextmanager
def plain_warnings():
    """While a command runs, a warning is one ``warning: message`` line on stderr, as the
    commands' own warnings are (Python's format adds the package's file, line and source line,
    which tell a user nothing); the caller's warning display is restored after."""
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        yield


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _without_cache(args) -> int:
    before = os.environ.get("BAYESUPDATE_NO_CACHE")
    os.environ["BAYESUPDATE_NO_CACHE"] = "1"
    try:
        return int(args._run(args) or 0)
    finally:
        if before is None:
            del os.environ["BAYESUPDATE_NO_CACHE"]
        else:
            os.environ["BAYESUPDATE_NO_CACHE"] = before


if __name__ == "__main__":
    sys.exit(main())
