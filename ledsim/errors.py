"""Errors that mean "the user asked for something invalid": one line, exit code 2."""


class UserError(Exception):
    """Bad user input, reported by the CLI as one line with exit code 2."""
