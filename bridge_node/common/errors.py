"""Errors that are the user's to fix: printed as one message, never as a traceback."""


class UserError(Exception):
    """A bad argument or input file; the message says what is wrong and what is allowed."""

