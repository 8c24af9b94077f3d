"""The calibration's figure (eval/calibrate_uncertainty.py --figure): per (scene, noise), the
actual errors of the trials against the 95 % ellipses of each method's mean reported covariance,
and the first trial's samples."""

from pathlib import Path

import numpy as np

# The 2-D marginals drawn per (scene, noise): translation x-y in mm, rotation pitch-yaw in deg.
PANELS = (((0, 1), 1e3, "x error (mm)", "y error (mm)"),
          ((4, 5), np.degrees(1.0), "pitch error (deg)", "yaw error (deg)"))
CHI2_95_2DOF = 5.991  # the 95 % ellipse of a 2-D Gaussian


def ellipse_xy(mean2, cov2, radius: float, n: int = 100) -> np.ndarray:
    """(n, 2) points of the Mahalanobis-radius contour of a 2-D Gaussian (a semi-definite
    covariance gives a flat ellipse)."""
    vals, vecs = np.linalg.eigh(cov2)
    t = np.linspace(0, 2 * np.pi, n)
    circle = np.c_[np.cos(t), np.sin(t)] * (radius * np.sqrt(np.maximum(vals, 0)))
    return np.asarray(mean2) + circle @ vecs.T


def draw_figure(figure_data: dict, path: Path) -> None:
    """Per (scene, noise): the actual errors of every valid trial of the first method (dots), the
    95 % ellipse of each method's mean reported covariance around zero, and the first trial's
    samples / particles (as errors). One row per (scene, noise): pick a few with --datasets and
    --noise."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(figure_data)
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 4.2 * len(names)), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for row, name in enumerate(names):
        errors, mean_covs, first_samples = figure_data[name]
        for col, (axes_idx, unit, xlabel, ylabel) in enumerate(PANELS):
            ax = axes[row, col]
            idx = list(axes_idx)
            ax.scatter(errors[:, idx[0]] * unit, errors[:, idx[1]] * unit, s=10, c="0.35",
                       label=f"actual errors ({len(errors)} trials)", zorder=3)
            if len(errors):
                actual = errors[:, idx].T @ errors[:, idx] / len(errors)
                e = ellipse_xy(np.zeros(2), actual * unit**2, np.sqrt(CHI2_95_2DOF)).T
                ax.plot(*e, c="k", lw=2.2, ls="--", label="95 % of the actual errors")
            for k, m in enumerate(mean_covs):
                c = colours[k % len(colours)]
                e = ellipse_xy(np.zeros(2), mean_covs[m][np.ix_(idx, idx)] * unit**2,
                               np.sqrt(CHI2_95_2DOF)).T
                ax.plot(*e, c=c, lw=1.6, ls=":" if "naive" in m else "-",
                        label=f"{m}: mean reported 95 %")
                if first_samples and m in first_samples:
                    smp = first_samples[m]
                    ax.scatter(smp[:, idx[0]] * unit, smp[:, idx[1]] * unit, s=9, color=c,
                               alpha=0.5, marker="x" if m.startswith("svgd") else ".",
                               label=f"{m}: trial 0 samples")
            ax.set(xlabel=xlabel, ylabel=ylabel, title=name)
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(alpha=0.3)
        axes[row, 1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    print(f"wrote {path}")
