"""Errors the toolkit raises for input it cannot use (the CLI maps them to exit code 2)."""


class InputError(ValueError):
    """Bad input: says what was found and what was expected, in one line."""
