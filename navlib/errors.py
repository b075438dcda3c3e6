"""The one exception type user-facing calls raise for bad input."""


class NavlibInputError(ValueError):
    """Bad input to a user-facing navlib call.

    The message names the offending argument, column, row or file and what was expected.
    It subclasses :class:`ValueError` so generic handlers keep working.
    """
