"""Errors the toolkit raises (the CLI maps them to exit codes and a one-line message)."""


class InputError(ValueError):
    """Bad input (exit code 2): says what was found and what was expected, in one line."""


class NumericalError(ArithmeticError):
    """A numerical outcome, not bad input (exit code 1): the inputs were valid, but the computation
    cannot go on there, e.g. M_r singular at a configuration, an integrator that fails, rigid
    contacts whose KKT system is singular, or another library disagreeing with Pinocchio.
    Says what failed and where, in one line."""


class BuildError(RuntimeError):
    """A compiler or harness failed (exit code 1): says which command and why. A missing
    compiler is an InputError (exit code 2): the environment, not a check, is wrong."""


class UrdfWarning(UserWarning):
    """A URDF oddity that does not change the answers (e.g. an unphysical inertia of a link
    merged into a physical body); the CLI prints it as one line."""
