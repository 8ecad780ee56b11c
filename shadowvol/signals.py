"""Ctrl-C and SIGTERM for the command-line tools: never a finished file after an interrupt.

`handled()` (around both CLIs' main) makes SIGINT raise KeyboardInterrupt and SIGTERM raise
`Terminated`, and remembers that the signal came.  Some libraries swallow exceptions around
their imports (trimesh guards optional imports with `except BaseException`), so an interrupt in
the first fraction of a second could vanish and the command finish with status 0; the writer
therefore asks `raise_pending()` before it renames a file into place, and the CLI asks again
before it reports success.

The handler never raises where the exception could not propagate (`_unsafe`): inside a Python
function that C code calls and whose result it does not check (moderngl's, where it was a
SIGSEGV), a finalizer, or importlib's lock callback; it answers the signal again 10 ms later.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading


class Terminated(BaseException):
    """SIGTERM arrived (the command exits with status 143)."""


class _Pending:
    """The signal that arrived and has not yet stopped the command, and how deep `handled` is
    nested (process facts)."""
    signum: int | None = None
    depth: int = 0
    deferred: int | None = None  # the signal `_handler` will answer again (`_again`)


# Where an exception raised by the handler is not propagated but printed as "Exception ignored
# in ..." with a traceback: importlib's module-lock weakref callback (`_get_module_lock.cb`),
# which runs whenever a module lock is collected, during any import.
_IGNORING = {("<frozen importlib._bootstrap>", "cb")}
# Modules whose functions C code calls and whose result it does not check: moderngl's
# `Context.program` (C) calls `_moderngl.make_attribute`, `make_uniform`, ... once per name of
# the program it linked and stores what comes back unchecked.  A signal that arrives while the
# driver compiles or links (no bytecode runs then) is answered at the first line of that
# callback; raised there, it is a NULL that moderngl dereferences: SIGSEGV (seen after a SIGINT
# to a batch, `benchmarks/signal_in_compile.py` reproduces it in a few signals).
_CALLED_FROM_C = frozenset({"_moderngl"})
REDELIVER_S = 0.01  # a signal that lands there comes again this much later


def _unsafe(frame) -> bool:
    """Whether an exception raised in `frame` would be lost or crash the process: a frame of
    `_IGNORING`, one inside a call from C that does not check it (`_CALLED_FROM_C`), or inside
    a finalizer (`__del__`: moderngl's objects have one; Python prints what it raises as
    "Exception ignored in ..." with a traceback, and drops it)."""
    if frame is not None and (frame.f_code.co_filename, frame.f_code.co_name) in _IGNORING:
        return True
    while frame is not None:
        if frame.f_code.co_name == "__del__" or frame.f_globals.get("__name__") in _CALLED_FROM_C:
            return True
        frame = frame.f_back
    return False


def _again(signum: int) -> None:
    """The deferred signal once more, unless it was answered meanwhile (`raise_pending`, the
    end of `handled`) or Python no longer catches it (`finished`: the CLI's `raise_pending`
    reports it).  A real signal, not `_thread.interrupt_main`, which wakes no blocking wait."""
    if _Pending.deferred == signum and callable(signal.getsignal(signum)):
        os.kill(os.getpid(), signum)


def _handler(signum, frame):
    _Pending.signum = signum
    if _unsafe(frame):
        # raising here would print a traceback and lose the exception, or crash: answer the
        # signal again in a moment, when the main thread is back in code that propagates it
        _Pending.deferred = signum
        timer = threading.Timer(REDELIVER_S, _again, (signum,))
        timer.daemon = True
        timer.start()
        return
    _Pending.deferred = None
    raise KeyboardInterrupt() if signum == signal.SIGINT else Terminated()


def keyboard_interrupt() -> None:
    """SIGINT raises KeyboardInterrupt, as Python's own handler does, but never where raising
    would crash (`_unsafe`): for a process that has no `handled` block, a batch's pool worker
    (a Ctrl-C in a terminal reaches the whole process group).  Main thread only."""
    signal.signal(signal.SIGINT, _handler)


@contextlib.contextmanager
def handled(restore: bool = True):
    """While inside: SIGINT -> KeyboardInterrupt, SIGTERM -> Terminated, both remembered.  The
    previous handlers come back on the way out unless `restore` is False (a console script,
    whose process ends with the command: see `finished`).  A nested use shares the outermost's
    handlers and memory.  Only the main thread may install handlers (Python's rule);
    elsewhere this changes nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _Pending.depth:
        _Pending.depth += 1
        try:
            yield
        finally:
            _Pending.depth -= 1
        return
    _Pending.signum, _Pending.depth, _Pending.deferred = None, 1, None
    previous = signal.signal(signal.SIGINT, _handler), signal.signal(signal.SIGTERM, _handler)
    try:
        yield
    finally:
        _Pending.depth = 0
        if restore:
            signal.signal(signal.SIGINT, previous[0])
            signal.signal(signal.SIGTERM, previous[1])
            # the block has answered its signal: left pending, it would stop every later atomic
            # write of this process (`raise_pending`), in code that never saw it
            _Pending.signum = _Pending.deferred = None


@contextlib.contextmanager
def deferred():
    """While inside, SIGINT and SIGTERM are remembered, not raised; on the way out the first
    that came is raised again through the handlers that were there before (those of `handled`,
    or Python's).  For the few lines that must not be cut in half: a child process being
    started, which once cut is left behind (it then dies reading its half-sent start-up data,
    printing a traceback).  Only the main thread can install handlers; elsewhere it defers
    nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []

    def remember(signum, frame):
        came.append(signum)

    previous = signal.signal(signal.SIGINT, remember), signal.signal(signal.SIGTERM, remember)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])
        if came:
            signal.raise_signal(came[0])


def finished() -> None:
    """The command has returned and the process is about to end: from now on a signal kills it
    the default way (status -N).  Once the interpreter shuts down no Python handler runs, so a
    caught signal would be lost and the status would say success."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def pending() -> BaseException | None:
    """The interrupt that arrived (KeyboardInterrupt or Terminated), or None.  An interrupt
    inside an import can surface as another exception (numpy turns it into ImportError): the
    CLI reports the interrupt then, not what it broke."""
    signum = _Pending.signum
    if signum is None:
        return None
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated()


def raise_pending() -> None:
    """Raise again an interrupt that arrived and was swallowed on its way up."""
    exc = pending()
    if exc is not None:
        _Pending.deferred = None  # answered now: not again
        raise exc
