"""The ``skyscatter`` command line. One module per subcommand, each with ``register(subparsers)``.

Errors a user can cause (bad values, unreadable or unwritable files) print one line on stderr and exit with
status 2; nothing is partly written. Warnings print as one line each. SIGINT and SIGTERM stop the command
cleanly (temporary files removed; exit status 130 and 143). Every option that takes a value accepts one that
starts with '-' (``--turbidity -inf``, ``--time -2000-01-01T00:00Z``), so the value's own check says what is
wrong with it.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
from collections.abc import Iterator, Sequence

from .. import __version__
from ..errors import SkyscatterError

# Subcommand modules in the order ``--help`` lists them.
_COMMANDS = ["sun", "sky", "illuminance", "skymatrix", "demo", "precompute", "export_luts", "view", "reference",
             "fit_hosek_wilkie", "fit_atmosphere"]
# Each module registers one subcommand, named like the module with '-' for '_'.
_MODULE_OF = {name.replace("_", "-"): name for name in _COMMANDS}
# Commands whose linear algebra is a few small products: their BLAS pool starts with one thread (below).
_SMALL_BLAS_COMMANDS = ("sun", "sky", "illuminance", "skymatrix")
_BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "GOTO_NUM_THREADS")


def _one_blas_thread_for(command: str | None) -> None:
    """Start numpy's BLAS with one thread for a command that only multiplies small matrices.

    OpenBLAS starts a thread per core when numpy is imported and keeps it spinning for a while: about 0.06 s of
    a two-core machine, more with more cores, all for nothing in these commands (a quick command line:
    docs/architecture.md, "Start-up"). Only before numpy is imported and only if the user has set none of the BLAS
    thread variables; :func:`skyscatter.runtime.set_num_threads` still sizes the pool later if a computation asks for
    it.
    """
    if (command in _SMALL_BLAS_COMMANDS and "numpy" not in sys.modules
            and not any(v in os.environ for v in _BLAS_THREAD_VARIABLES)):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are a single line, ``skyscatter <cmd>: error: ...``."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)  # "--tilt" must not silently mean "--tilted"
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        """Join ``--option -value`` into ``--option=-value`` for options taking one value, so that argparse
        does not take a value starting with '-' (a negative number, ``-inf``, a date before year 0) for an
        option. A following token that is itself one of this parser's options is left alone."""
        if args is None:
            args = sys.argv[1:]
        return super().parse_known_args(self._join_dash_values(list(args)), namespace)

    def _join_dash_values(self, args: list[str]) -> list[str]:
        takes_one = {s for a in self._actions if a.option_strings and a.nargs is None for s in a.option_strings}
        known = set(self._option_string_actions)
        out: list[str] = []
        i = 0
        while i < len(args):
            tok = args[i]
            if tok == "--":
                out.extend(args[i:])
                break
            nxt = args[i + 1] if i + 1 < len(args) else None
            if (tok in takes_one and nxt is not None and nxt.startswith("-") and nxt != "--"
                    and nxt.split("=", 1)[0] not in known):
                out.append(f"{tok}={nxt}")
                i += 2
                continue
            out.append(tok)
            i += 1
        return out


class Terminated(KeyboardInterrupt):
    """Raised in the main thread on SIGTERM so that ``finally`` blocks and temporary-file cleanup run."""


@contextlib.contextmanager
def _cli_environment() -> Iterator[None]:
    """One-line warnings and SIGTERM as an exception, for the duration of a command."""

    from .common import one_line_warnings

    def on_sigterm(signum, frame):
        raise Terminated()

    previous = None
    with contextlib.suppress(ValueError):  # not the main thread: leave signals alone
        previous = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        with one_line_warnings():
            yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser with every subcommand, or with ``command`` alone (when it names one): a command then imports
    only its own module and what that needs (a quick command line). ``--help``, a missing or an
    unknown command get the full parser, so that the listing and "invalid choice" name every command."""
    from .common import HelpFormatter

    parser = OneLineParser(
        prog="skyscatter",
        description="Physically based daylight: sun position, sky models, sky images and landscapes.",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"skyscatter {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    for name in [_MODULE_OF[command]] if command in _MODULE_OF else _COMMANDS:
        module = importlib.import_module(f"skyscatter.cli.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; returns the exit status (for calling the command line from Python)."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    name = args_list[0] if args_list and args_list[0] in _MODULE_OF else None
    with _cli_environment():
        try:
            return _main(args_list)
        except BaseException as exc:  # an interruption anywhere: parsing, a lazy import, the command, its output
            interruption = _interruption(exc)
            if interruption is None:
                raise
            word, code = ("terminated", 143) if isinstance(interruption, Terminated) else ("interrupted", 130)
            print(f"skyscatter{' ' + name if name else ''}: {word}", file=sys.stderr)
            return code


def _interruption(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl-C) or Terminated (SIGTERM) behind ``exc``: itself, or the cause of an error it
    turned into (Ctrl-C while a C extension initialises surfaces as ``ImportError: initialization failed``)."""
    seen = 0
    while exc is not None and seen < 16:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def console_main() -> None:
    """The ``skyscatter`` executable: :func:`main`, then exit with its status.

    After an interruption (Ctrl-C, SIGTERM: status 130 or 143) the process ends at once, once the command's own
    clean-up has run (temporary files removed, locks released): the interpreter's finalisation (tearing down the
    imported numerical libraries, up to a few seconds) and any computation still running in worker threads are
    skipped, so that the command stops within a second.
    """
    code = main()
    if code in (130, 143):
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def _main(args_list: list[str]) -> int:
    command = args_list[0] if args_list else None
    _one_blas_thread_for(command)
    parser = build_parser(command)
    try:
        args = parser.parse_args(args_list)
    except SystemExit as exc:  # --help, --version and usage errors (already printed)
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except SkyscatterError as exc:
        print(f"skyscatter {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        if _interruption(exc) is not None:
            raise
        print(f"skyscatter {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
              file=sys.stderr)
        return 2
    except MemoryError:
        print(f"skyscatter {args.command}: error: not enough memory; use a smaller image or table size",
              file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    console_main()
