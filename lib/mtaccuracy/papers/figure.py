"""A figure's caption, declared in its paper module beside the code that draws it."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Caption:
    """What the book shows under a figure, and the file it is saved as.

    Parameters
    ----------
    name : str
        The file name without extension, after the paper's figure (``fig05_position_total_sobol``).
    label : str
        The paper's figure number (``"Fig. 5"``), ``"Beyond the paper"`` for a figure the paper
        does not have, or ``"Figure N"`` in a chapter without a paper.
    text : str
        The caption: what is drawn, at which pose or setting, on which data.  It may hold
        ``{fields}`` that :meth:`format` fills with numbers the run computed.
    rows : tuple of str
        Patterns (:mod:`fnmatch`, on a scorecard row's ``item`` or ``"item: quantity"``) of the
        rows that score what the figure shows, where its name is not their item.
    key : bool
        The chapter's key figure: the one the book's home shows beside the paper's finding.
    """

    name: str
    label: str
    text: str
    rows: tuple[str, ...] = ()
    key: bool = False

    def format(self, **values) -> Caption:
        """The caption with its ``{fields}`` filled."""
        return Caption(self.name, self.label, self.text.format(**values), self.rows, self.key)


def figures(*captions: Caption) -> dict[str, Caption]:
    """A chapter's captions by file name, in the paper's order (the book's order)."""
    out = {c.name: c for c in captions}
    if len(out) != len(captions):
        raise ValueError("two captions name the same file")
    return out
