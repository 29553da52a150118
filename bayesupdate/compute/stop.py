"""Cooperative interruption: a SIGTERM / SIGINT handler records the request, long loops check it.

Why: the handler raises ``KeyboardInterrupt`` where the signal lands, but a compiled extension
may swallow it (scipy's Sobol initialization reports "Exception ignored" and carries on), and
the run would then finish as if never asked to stop.  The recorded request is checked again at
safe points (between optimizer starts, between sampler steps), so the stop always happens;
``quiet_unraisable`` keeps the extension's "Exception ignored" report off the terminal, and
``quiet_excepthook`` the traceback a Cython function prints first (``__Pyx_WriteUnraisable``
calls ``PyErr_PrintEx``, i.e. ``sys.excepthook``, before the unraisable hook).

Inside ``deferred()`` the handler only records the request: the sampler's bookkeeping between
blocks and its checkpoint writes must not be cut in half (a stop landing there used to end the
run with a bare "interrupted" and no resume hint, although the last checkpoint was valid).  The
sampler's emcee steps run deferred too, and only its model calls inside them are
``interruptible()``: a KeyboardInterrupt raised in emcee's own code around a model call made
emcee print "Exception while calling your likelihood function" and a traceback (seen on a
2-core machine under load, where the Ctrl-C test of ``sample`` landed there once in a suite).
"""

import sys
from contextlib import contextmanager


class StopRequest:
    """One run's stop request: the command installs ``handler`` for SIGTERM/SIGINT and passes
    the object down (``calibrate``, ``sample_posterior``); long loops ``check()`` it at safe
    points.  Nothing is global: a run nobody can signal gets a fresh one.

    A run can also stop itself on an error met where raising would cut a step in half (the
    sampler's log-density inside emcee, e.g. a lost Dask scheduler): ``fail(error)`` records
    the error and requests the stop; the run raises ``error`` once its state is safe."""

    def __init__(self):
        self._requested = False
        self._deferred = False
        self._error: Exception | None = None

    def request(self) -> None:
        """Record a stop request (called from the signal handler)."""
        self._requested = True

    def requested(self) -> bool:
        return self._requested

    def fail(self, error: Exception) -> None:
        """Record ``error`` (raised later by the run, ``error``) and request the stop."""
        self._error = error
        self._requested = True

    @property
    def error(self) -> Exception | None:
        """The error recorded by ``fail``, or None."""
        return self._error

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a stop was requested."""
        if self._requested:
            raise KeyboardInterrupt

    def deferred(self):
        """While the block runs, ``handler`` records a stop request without raising; the caller
        checks ``requested()`` after the block."""
        return self._deferring(True)

    def interruptible(self):
        """Inside ``deferred()``, a block where ``handler`` raises again: a long model call that
        a stop may cut, inside a caller that catches the ``KeyboardInterrupt``."""
        return self._deferring(False)

    @contextmanager
    def _deferring(self, deferred: bool):
        previous, self._deferred = self._deferred, deferred
        try:
            yield
        finally:
            self._deferred = previous

    def handler(self, _signum, _frame) -> None:
        """A signal handler: record the request and interrupt where the signal lands (unless
        inside ``deferred()``)."""
        self.request()
        if not self._deferred:
            raise KeyboardInterrupt

    def quiet_unraisable(self, unraisable) -> None:
        """``sys.unraisablehook`` that drops the "Exception ignored" report of a swallowed stop
        request (the request itself is recorded and acted on); anything else goes to the
        default."""
        if isinstance(unraisable.exc_value, KeyboardInterrupt) and self.requested():
            return
        sys.__unraisablehook__(unraisable)

    def quiet_excepthook(self, exc_type, exc_value, traceback) -> None:
        """``sys.excepthook`` that drops the traceback of a swallowed stop request; anything
        else goes to the default."""
        if issubclass(exc_type, KeyboardInterrupt) and self.requested():
            return
        sys.__excepthook__(exc_type, exc_value, traceback)
