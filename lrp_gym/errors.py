"""Exceptions the CLI turns into a clear message and exit code 2."""


class InputError(ValueError):
    """Bad user input (argument, file, model) that is not a scenario validation problem."""
