"""Large arguments that cross the channel to a worker once: the worker keeps them.

A growth check (:mod:`grader.oracles.scaling`) calls several functions, several
times each, on the same scenes of thousands of boxes; sent whole each time, they
made a third of a submission's requests.  An argument wrapped in :class:`KeptArgument`
is sent once to each worker process, as ``{KEEP_TAG: key, "value": plain}``: the
worker keeps the plain value under ``key`` and decodes a fresh copy for each call, and
later requests send only ``{KEPT_TAG: key}``.

The trusted side decides what the worker holds (:class:`KeptValues`, one per worker
process: a restarted worker holds nothing); the worker only stores what it is told
to and never evicts.  A worker whose store was changed by the student's code decodes
a wrong value or none, which fails that student's own call: the answers are checked
by the trusted side as any other.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, Callable

from .codec import KEEP_TAG, KEPT_TAG

#: Most numbers (floats, ints) one worker keeps: 2 million, about 16 MB of floats once
#: decoded; an argument that would pass it is sent whole every time.
KEPT_NUMBERS_LIMIT = 2_000_000


@dataclass(frozen=True)
class KeptArgument:
    """An argument for the worker to keep: ``key`` names its content (equal keys, equal
    values), ``plain()`` encodes it (called only when it has to be sent), ``numbers``
    counts what it holds (against :data:`KEPT_NUMBERS_LIMIT`)."""

    key: str
    plain: Callable[[], Any]
    numbers: int


def kept_array(array, encode: Callable[[Any], Any]) -> KeptArgument:
    """``array`` (numpy) as a :class:`KeptArgument`, keyed by its dtype, shape and bytes."""
    digest = hashlib.sha256(f"{array.dtype.str}{array.shape}".encode())
    digest.update(array.tobytes())
    return KeptArgument(digest.hexdigest(), lambda: encode(array), int(array.size))


class KeptValues:
    """What one worker process holds, from the trusted side."""

    def __init__(self):
        self.keys: set[str] = set()
        self.numbers = 0

    def form(self, argument: Any) -> Any:
        """The request form of one argument: a :class:`KeptArgument` as a reference to
        what the worker holds, or with its value to keep (now marked held), or plain
        when the limit is reached; anything else as it is."""
        if type(argument) is not KeptArgument:
            return argument
        if argument.key in self.keys:
            return {KEPT_TAG: argument.key}
        if self.numbers + argument.numbers > KEPT_NUMBERS_LIMIT:
            return argument.plain()
        self.keys.add(argument.key)
        self.numbers += argument.numbers
        return {KEEP_TAG: argument.key, "value": argument.plain()}
