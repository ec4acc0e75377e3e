"""The ``skyscatter`` command line. One module per subcommand, each with ``register(subparsers)``.

Errors a user can cause (bad values, unreadable or unwritable files) print one line on stderr and exit with
status 2; nothing is partly written.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .. import __version__
from ..errors import SkyscatterError

# Subcommand modules in the order ``--help`` lists them.
_COMMANDS = ["sun", "sky", "illuminance", "skymatrix", "demo", "precompute", "export_luts", "reference",
             "fit_hosek_wilkie"]


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are a single line, ``skyscatter <cmd>: error: ...``."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)  # "--tilt" must not silently mean "--tilted"
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="skyscatter",
        description="Physically based daylight: sun position, sky models, sky images and landscapes.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"skyscatter {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    for name in _COMMANDS:
        module = importlib.import_module(f"skyscatter.cli.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``skyscatter`` command; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
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
        print(f"skyscatter {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
              file=sys.stderr)
        return 2
    except MemoryError:
        print(f"skyscatter {args.command}: error: not enough memory; use a smaller image or table size",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"skyscatter {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
