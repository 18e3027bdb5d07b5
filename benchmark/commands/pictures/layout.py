"""Fixed figure margins in inches: the layout ``tight_layout`` finds, without drawing the figure twice.

``Figure.tight_layout`` draws the whole figure once to measure its text and then ``savefig`` draws it
again: for the main command's Fig. 4 and Fig. 5 that first draw is about a third of each picture's
time (0.3 s of 0.8 s and 0.25 s of 0.5 s on this machine), and the pictures are what the command
waits for at its end. Their panels, labels and legends are fixed, so their margins are too: given
here in inches (a figure's size may change), measured once from ``tight_layout`` with room for
wider tick labels. ``tests/test_layout.py`` draws each figure and checks that no text leaves the
figure and that no two panels' labels overlap.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Margins:
    """A figure's margins and the gaps between its panels.

    Attributes:
        left_in, right_in, bottom_in, top_in: Margins to the figure's edges [in].
        title_in: What a figure title adds to the top margin [in].
        wspace, hspace: Gaps between panels, as fractions of the mean panel width and height
            (matplotlib's ``subplots_adjust``).
    """

    left_in: float
    right_in: float
    bottom_in: float
    top_in: float
    title_in: float = 0.0
    wspace: float = 0.2
    hspace: float = 0.2

    def apply(self, fig, titled: bool = False) -> None:
        """Sets ``fig``'s subplot parameters (a ``matplotlib.figure.Figure``) to these margins, with
        room for a figure title if ``titled``."""
        width, height = fig.get_size_inches()
        top = self.top_in + (self.title_in if titled else 0.0)
        if self.left_in + self.right_in >= width or self.bottom_in + top >= height:
            raise ValueError(f"margins {self} leave no room in a {width:g} x {height:g} in figure")
        fig.subplots_adjust(left=self.left_in / width, right=1 - self.right_in / width,
                            bottom=self.bottom_in / height, top=1 - top / height,
                            wspace=self.wspace, hspace=self.hspace)
