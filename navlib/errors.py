"""The one exception type user-facing calls raise for bad input, and the one warning category
of flight data that were accepted with a finding."""

__all__ = ["FlightDataWarning", "NavlibInputError"]


class NavlibInputError(ValueError):
    """Bad input to a user-facing navlib call.

    The message names the offending argument, column, row or file and what was expected.
    It subclasses :class:`ValueError` so generic handlers keep working.
    """


class FlightDataWarning(UserWarning):
    """Flight data were accepted but something was found (gaps, fallbacks, corruption).

    Defined here, beside :class:`NavlibInputError`, so every reader module can raise it
    without importing another (``navlib.io`` exports it)."""
