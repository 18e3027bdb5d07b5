"""A figure like the paper's Fig. 4: vision kinematics against the AHRS, six axes."""

from __future__ import annotations

import io
import os
from pathlib import Path

from benchmark.atomic import write_bytes
from benchmark.commands.pictures.layout import Margins
from benchmark.errors import ScenarioError
from benchmark.world.truth import Truth


def plot_fig4(truth: Truth, kinematics: dict, path: str | os.PathLike, title: str = "", panels: list | None = None) -> Path:
    """A figure like the paper's Fig. 4: vision kinematics against the AHRS, six axes.

    Args:
        truth: The truth (AHRS readings ``imu_acc``, ``imu_gyro``).
        kinematics: label -> Kinematics to draw (e.g. the three methods).
        path: Where to write the PNG (atomically).
        title: Figure title.
        panels: Optional six (truth, kinematics, subtitle) triples, one per panel in the order
            acc x, y, z, gyro x, y, z (e.g. each axis from the excitation of that axis); they
            replace ``truth`` and ``kinematics`` panel by panel.

    Returns:
        The written path.
    """
    import matplotlib  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    if panels is not None and len(panels) != 6:
        raise ScenarioError(f"plot_fig4 needs 6 panels (acc x, y, z, gyro x, y, z), got {len(panels)}")
    fig, axes = plt.subplots(2, 3, figsize=(13, 6))
    styles = {"central": ("tab:red", 0.6, "-"), "algebraic": ("tab:blue", 1.6, "-"), "gaussian": ("tab:green", 1.0, ":")}
    for row, (unit, key) in enumerate((("m/s$^2$", "imu_acc"), ("rad/s", "imu_gyro"))):
        for ax_i, axis in enumerate("xyz"):
            tr, kins, sub = panels[3 * row + ax_i] if panels is not None else (truth, kinematics, "")
            ax = axes[row, ax_i]
            for label in sorted(kins, key=lambda m: list(styles).index(m) if m in styles else 9):
                kin = kins[label]
                acc, gyro = kin.imu(tr.gravity)
                est = (acc if row == 0 else gyro)[:, ax_i]
                color, width, ls = styles.get(label, ("tab:purple", 1.0, "-"))
                ax.plot(kin.t[kin.valid], est[kin.valid], color=color, lw=width, ls=ls, label=f"vision, {label}")
            ax.plot(tr.t, getattr(tr, key)[:, ax_i], color="k", lw=1.2, ls="--", label="AHRS (truth)")
            name = "Translational acceleration" if row == 0 else "Rotational velocity"
            ax.set_title(f"{name} {axis}" + (f" ({sub})" if sub else ""), fontsize=10)
            ax.set_ylabel(unit)
            ax.set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    MARGINS.apply(fig, titled=bool(title))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes(path, buf.getvalue())
    return path


MARGINS = Margins(left_in=0.85, right_in=0.15, bottom_in=0.6, top_in=0.35, title_in=0.35, wspace=0.27, hspace=0.42)
"""Fig. 4's margins (:mod:`benchmark.commands.pictures.layout`): ``tight_layout`` gave 0.79, 0.15,
0.59, 0.25 in (0.66 under a title) and 0.25, 0.39 on the default lift; room here for tick labels a
digit wider."""
