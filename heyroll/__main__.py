"""The ``heyroll`` command (and ``python -m heyroll``): the command line of heyroll.interfaces.cli.

This module imports nothing heavy itself: a Ctrl-C while heyoka and matplotlib load ends the command with one line
and exit code 130, not a traceback. :func:`console`, the script's entry, then ignores a Ctrl-C landing while the
interpreter shuts down (the outputs were whole when the command returned); :func:`main` leaves the signal alone,
for callers in a longer-lived process.
"""

import signal
import sys

EXIT_INTERRUPTED = 130


def main(argv: list[str] | None = None) -> int:
    try:
        from heyroll.interfaces.cli import main as command
    except KeyboardInterrupt:
        print("heyroll: interrupted while starting: nothing was run or written", file=sys.stderr)
        return EXIT_INTERRUPTED
    return command(argv)


def console() -> int:
    code = main()
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: nothing to guard
        pass
    return code


if __name__ == "__main__":
    sys.exit(console())
