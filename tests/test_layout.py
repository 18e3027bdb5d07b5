"""Fixed margins (benchmark.commands.pictures.layout): Fig. 4 and Fig. 5 drawn without tight_layout
keep every text inside the figure and no two panels' labels on each other, with small and wide
tick labels and with and without a title."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from forces_oracle import grasp_truth

from benchmark.commands.pictures import fig4, fig5, layout
from fsv import Kinematics
from fsv.forces import nominal_forces

matplotlib.use("Agg")


def _kin(truth, scale: float = 1.0):
    return Kinematics(truth.t, truth.box_pos, truth.box_rot, truth.box_vel, scale * truth.box_acc, truth.box_omega,
                      truth.box_alpha, np.ones(len(truth.t), bool), "oracle")


@pytest.fixture
def drawn(monkeypatch):
    """The figures the plotting functions lay out, kept after they are written."""
    figures = []
    apply = layout.Margins.apply

    def keep(self, fig, titled=False):
        figures.append(fig)
        apply(self, fig, titled)

    monkeypatch.setattr(layout.Margins, "apply", keep)
    return figures


def check_layout(fig) -> None:
    """Draws ``fig`` and fails if a text leaves it or two panels (with their labels) meet."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # the written figure, closed by pyplot: drawn again here
    canvas.draw()
    renderer = canvas.get_renderer()
    W, H = fig.bbox.width, fig.bbox.height
    # what is drawn: each panel with its tick labels, axis labels, title and legends, and the figure's title
    boxes = [ax.get_tightbbox(renderer) for ax in fig.axes if ax.get_visible()]
    drawn_text = [t.get_window_extent(renderer) for t in fig.texts if t.get_visible() and t.get_text().strip()]
    for b in boxes + drawn_text:
        assert b.x0 >= -0.5 and b.y0 >= -0.5 and b.x1 <= W + 0.5 and b.y1 <= H + 0.5, (b.bounds, (W, H))
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            overlap_x = min(a.x1, b.x1) - max(a.x0, b.x0)
            overlap_y = min(a.y1, b.y1) - max(a.y0, b.y0)
            assert overlap_x <= 0.5 or overlap_y <= 0.5, (a.bounds, b.bounds)


@pytest.mark.parametrize("title", ["", "Vision kinematics vs AHRS (tracked poses (fsv.track, from depth))"])
@pytest.mark.parametrize("scale", [1.0, 30.0])
def test_fig4_keeps_its_labels_inside_and_apart(drawn, tmp_path, title, scale):
    truth, _ = grasp_truth(3, T=40, K=4)
    truth = type(truth)(**{**truth.__dict__, "imu_acc": scale * truth.imu_acc})
    fig4.plot_fig4(truth, {"algebraic": _kin(truth, scale), "central": _kin(truth, -scale)}, tmp_path / "f4.png",
                   title=title)
    assert len(drawn) == 1 and len(drawn[0].axes) == 6
    check_layout(drawn[0])


@pytest.mark.parametrize("title", ["", "forces — kinematics: algebraic differentiation (L=7 frames, kappa=0.5, "
                                       "mu=0.5) on tracked poses; contacts: vision (reference tracker)"])
def test_fig5_keeps_its_labels_and_legends_inside_and_apart(drawn, tmp_path, title):
    from benchmark.world.contact_error import contacts_from_truth

    truth, model = grasp_truth(3, T=40, K=5)
    kin = _kin(truth)
    sol = nominal_forces(kin, contacts_from_truth(truth), model)
    fig5.plot_fig5(sol, truth, kin.rot, tmp_path / "f5.png", title=title)
    assert len(drawn) == 1 and len(drawn[0].axes) == 3
    check_layout(drawn[0])


def test_margins_that_leave_no_room_are_refused():
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(4, 3))
    try:
        with pytest.raises(ValueError, match="leave no room"):
            layout.Margins(left_in=2.5, right_in=2.0, bottom_in=0.5, top_in=0.5).apply(fig)
        margins = layout.Margins(left_in=1.0, right_in=0.5, bottom_in=0.6, top_in=0.3, title_in=1.8)
        margins.apply(fig)
        assert fig.subplotpars.left == pytest.approx(0.25) and fig.subplotpars.top == pytest.approx(0.9)
        margins.apply(fig, titled=True)
        assert fig.subplotpars.top == pytest.approx(0.3)
        with pytest.raises(ValueError, match="leave no room"):
            layout.Margins(left_in=1.0, right_in=0.5, bottom_in=0.6, top_in=0.3, title_in=2.2).apply(fig, titled=True)
    finally:
        plt.close(fig)
