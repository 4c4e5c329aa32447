"""Project exceptions.

Every error a user can cause with a file or an option is a :class:`MotosimError`. Its message
is one line that names the offending value and what was expected; the command line prints it
as is and exits with code 2.
"""

__all__ = ["MotosimError"]


class MotosimError(ValueError):
    """Invalid input: a parameter, an option, a file or a signal that the model cannot accept."""
