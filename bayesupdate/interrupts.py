"""Cooperative interruption: a SIGTERM / SIGINT handler records the request, long loops check it.

Why: the handler raises ``KeyboardInterrupt`` where the signal lands, but a compiled extension
may swallow it (scipy's Sobol initialisation reports "Exception ignored" and carries on), and
the run would then finish as if never asked to stop.  The recorded request is checked again at
safe points (between optimiser starts, between sampler steps), so the stop always happens;
``quiet_unraisable`` keeps the extension's "Exception ignored" report off the terminal, and
``quiet_excepthook`` the traceback a Cython function prints first (``__Pyx_WriteUnraisable``
calls ``PyErr_PrintEx``, i.e. ``sys.excepthook``, before the unraisable hook).

Inside ``deferred()`` the handler only records the request: the sampler's bookkeeping between
blocks and its checkpoint writes must not be cut in half (a stop landing there used to end the
run with a bare "interrupted" and no resume hint, although the last checkpoint was valid).
"""

import sys
from contextlib import contextmanager

_state = {"requested": False, "deferred": False}


def request() -> None:
    """Record a stop request (called from a signal handler)."""
    _state["requested"] = True


def clear() -> None:
    _state["requested"] = False


def requested() -> bool:
    return _state["requested"]


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a stop was requested."""
    if _state["requested"]:
        raise KeyboardInterrupt


def quiet_unraisable(unraisable) -> None:
    """``sys.unraisablehook`` that drops the "Exception ignored" report of a swallowed stop
    request (the request itself is recorded and acted on); anything else goes to the default."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt) and requested():
        return
    sys.__unraisablehook__(unraisable)


def quiet_excepthook(exc_type, exc_value, traceback) -> None:
    """``sys.excepthook`` that drops the traceback of a swallowed stop request; anything else
    goes to the default."""
    if issubclass(exc_type, KeyboardInterrupt) and requested():
        return
    sys.__excepthook__(exc_type, exc_value, traceback)


@contextmanager
def deferred():
    """While the block runs, ``stop_handler`` records a stop request without raising; the
    caller checks ``requested()`` after the block."""
    previous = _state["deferred"]
    _state["deferred"] = True
    try:
        yield
    finally:
        _state["deferred"] = previous


def stop_handler(_signum, _frame) -> None:
    """A signal handler: record the request and interrupt where the signal lands (unless inside
    ``deferred()``)."""
    request()
    if not _state["deferred"]:
        raise KeyboardInterrupt
