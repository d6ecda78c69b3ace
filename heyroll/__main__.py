"""The ``heyroll`` command (and ``python -m heyroll``): the command line of heyroll.interfaces.cli.

This module imports nothing heavy itself: a Ctrl-C while heyoka and matplotlib load ends the command with one line
and exit code 130, not a traceback. :func:`console`, the script's entry, then ignores a Ctrl-C landing while the
interpreter shuts down (the outputs were whole when the command returned); :func:`main` leaves the signal alone,
for callers in a longer-lived process.
"""

import os
import signal
import sys

EXIT_INTERRUPTED = 130


class _PipeSafe:
    """stdout whose reader may go away (``heyroll run ... | head -1``): output past that is dropped and the
    command goes on to write its files and exit as it would (it raised BrokenPipeError: a traceback, and a run
    stopped half-way; acceptance test)."""

    def __init__(self, stream):
        self._stream, self._gone = stream, False

    def write(self, text):
        if not self._gone:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._reader_gone()
        return len(text)

    def flush(self):
        if not self._gone:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._reader_gone()

    def _reader_gone(self):
        self._gone = True
        try:  # the interpreter's last flush of the real stream must not fail either
            os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
        except (OSError, ValueError):
            pass

    def __getattr__(self, name):
        return getattr(self._stream, name)


def main(argv: list[str] | None = None) -> int:
    try:
        from heyroll.interfaces.cli import main as command
    except KeyboardInterrupt:
        print("heyroll: interrupted while starting: nothing was run or written", file=sys.stderr)
        return EXIT_INTERRUPTED
    return command(argv)


def console() -> int:
    # (a closed stdout, `heyroll run ... >&-`, is None here: its output goes nowhere, the run goes on)
    sys.stdout = _PipeSafe(sys.stdout if sys.stdout is not None else open(os.devnull, "w"))
    code = main()
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: nothing to guard
        pass
    return code


if __name__ == "__main__":
    sys.exit(console())
