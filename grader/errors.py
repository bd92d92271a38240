"""The error of a batch that cannot start or go on: the message says why."""


class GradingError(RuntimeError):
    """The batch cannot start (output folder busy, sandbox unusable, a worker that cannot
    start); the message says why."""
