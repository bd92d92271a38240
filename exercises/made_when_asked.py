# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/made_when_asked.py on the instructor's side.
"""An attribute that can be given a recipe instead of a value.

The compiled soft step (``response/soft_step_numba.py`` of the instructor's edition) leaves its results
in arrays; making Python objects of them (contacts, figures) would cost more than the
step.  So it sets such attributes to a function of no arguments, and the first read
calls it and keeps what it returns.  Any other value is stored and read as usual.

>>> class Step:
...     figures = MadeWhenAsked()
>>> step = Step()
>>> step.figures = lambda: [1, 2]
>>> step.figures, step.figures is step.figures
([1, 2], True)
"""
from __future__ import annotations


class MadeWhenAsked:
    """A data descriptor: a callable value is called on the first read and replaced by its result."""

    def __set_name__(self, owner, name: str) -> None:
        self.slot = "_" + name

    def __get__(self, instance, owner=None):
        if instance is None:
            return self
        value = instance.__dict__[self.slot]
        if callable(value):
            value = instance.__dict__[self.slot] = value()
        return value

    def __set__(self, instance, value) -> None:
        instance.__dict__[self.slot] = value

    @staticmethod
    def set_recipes(instance, recipes: dict) -> None:
        """Set several such attributes of ``instance`` at once: ``recipes`` maps each
        attribute's storage slot (``"_" + name``) to its recipe.  One dictionary update,
        for a caller that sets them every step (a Python-level ``__set__`` costs about a
        tenth of a microsecond each).

        >>> class Step:
        ...     figures = MadeWhenAsked()
        >>> step = Step()
        >>> MadeWhenAsked.set_recipes(step, {"_figures": lambda: 3})
        >>> step.figures
        3
        """
        instance.__dict__.update(recipes)
