"""An FMU's log messages from FMPy's simulate_fmu, without leaving FMPy's logger proxy dangling.

FMPy 0.3.32 formats every FMI 2.0 log message in one process-wide C proxy that holds a single
pointer: the last logger handed to it. simulate_fmu(..., logger=f) points it at a ctypes thunk of
f that it drops when it returns, so the next FMU logging through FMPy's default callbacks (an SSP
run, FMPy's own simulate_fmu without a logger) calls freed memory and the process dies.
`collecting()` gives a logger for one call, then points the proxy back at FMPy's own printer,
through a thunk kept for the life of the process.
"""

from __future__ import annotations

from contextlib import contextmanager
from ctypes import byref

_printer = None  # (thunk, callbacks): created once, never freed


def _point_proxy_at(thunk, callbacks):
    # addLoggerProxy remembers callbacks.logger and replaces it by the proxy: hand it the thunk each time.
    from fmpy.logging import addLoggerProxy

    callbacks.logger = thunk
    addLoggerProxy(byref(callbacks))


def _point_proxy_at_printer():
    global _printer
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage

    if _printer is None:
        _printer = (fmi2CallbackLoggerTYPE(printLogMessage), fmi2CallbackFunctions())
    _point_proxy_at(*_printer)


class Log(list):
    """The messages an FMU logged, as text; `warnings`: those it logged as fmi2Warning or worse."""

    def __init__(self):
        super().__init__()
        self.warnings: list[str] = []


WARNING = 1  # fmi2Status: fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal


@contextmanager
def collecting():
    """`with collecting() as (messages, logger): simulate_fmu(..., logger=logger)`: each message
    the FMU logs is appended to `messages` (a Log) as text."""
    messages = Log()

    def logger(*args):  # (component, instance name, status, category, message)
        message = args[-1]
        text = message.decode(errors="replace") if isinstance(message, bytes) else str(message)
        messages.append(text)
        if len(args) >= 5 and args[2] >= WARNING:
            messages.warnings.append(text)

    try:
        yield messages, logger
    finally:
        _point_proxy_at_printer()


@contextmanager
def collecting_proxied():
    """For an instance made with FMPy's default callbacks (its messages go through the proxy), one
    kept across runs: `with collecting_proxied() as messages:` appends (status, text) of each message
    logged in the block, then points the proxy back at FMPy's printer."""
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    messages: list[tuple[int, str]] = []

    def logger(component, instance, status, category, message):
        messages.append((int(status), message.decode(errors="replace") if isinstance(message, bytes) else str(message)))

    thunk, callbacks = fmi2CallbackLoggerTYPE(logger), fmi2CallbackFunctions()  # alive for the block
    _point_proxy_at(thunk, callbacks)
    try:
        yield messages
    finally:
        _point_proxy_at_printer()
