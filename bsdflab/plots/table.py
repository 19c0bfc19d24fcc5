"""The table figure: in-plane slices of a tabulated BSDF with error bands, and an error map."""
from __future__ import annotations

import numpy as np

from bsdflab.plots.lobe import save_figure
from bsdflab.tables.data import TableData
from bsdflab.tables.summary import BOUND, EXACT, SIGNIFICANT, error_kind

MAX_CHANNEL_PANELS = 4  # spectral tables: a few wavelengths spread over the range
MAX_INCIDENCES = 4


def spread(n: int, k: int) -> np.ndarray:
    """Up to k indices spread evenly over range(n), both ends included."""
    return np.unique(np.linspace(0, n - 1, min(k, n)).round().astype(int))


def in_plane(a: np.ndarray, theta_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(signed theta_o, a) along the plane of incidence from a (n_theta_o, n_phi) slice.

    The light comes from the -x side: phi = 0 (back toward the light) is plotted at negative
    angles, phi = pi (the mirror side) at positive ones."""
    x = np.concatenate([-theta_o[::-1], theta_o])
    return x, np.concatenate([a[::-1, 0], a[:, -1]])


def _channel_label(table: TableData, c: int) -> str:
    name = table.channels[c]
    return f"channel {name}" if not table.spectral else f"lambda = {name} nm"


def table_figure(table: TableData, path: str, thickness_index: int = 0, source: str = "") -> str:
    """Write the figure for one film thickness of `table` to `path` (PNG, atomically);
    returns what its bands and curves show (the title's words).

    One row per lobe: per shown channel, f(theta_o) in the plane of incidence at a few
    theta_i with error bands (PFMC: +-2 standard errors; adding-doubling: +- the solver's
    deterministic bound); last, that relative error over theta_o x phi at the middle
    theta_i node (cells under 1 % of the table's maximum left blank). A split table
    (layered models) holds the scattered part only: the title says that the top's own
    reflection, its specular peak included, is added at lookup.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not 0 <= thickness_index < table.n_thickness:
        raise ValueError(f"thickness_index must be in [0, {table.n_thickness - 1}], got {thickness_index}")
    g = table.grid
    shown = spread(len(table.channels), MAX_CHANNEL_PANELS)
    incidences = spread(g.n_theta_i, MAX_INCIDENCES)
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, len(incidences)))
    deg_i, deg_o, deg_phi = np.degrees(g.theta_i), np.degrees(g.theta_o), np.degrees(g.phi)
    n_cols = len(shown) + 1
    fig, axes = plt.subplots(len(table.lobes), n_cols, figsize=(4.2 * n_cols, 3.6 * len(table.lobes)),
                             squeeze=False, constrained_layout=True)
    kind = error_kind(table)
    width, band = {BOUND: (1, "bands = +- the solver's deterministic bound"),
                   EXACT: (0, "exact cells (no error)")}.get(kind, (2, "bands = +-2 standard errors"))
    for row, lobe in enumerate(table.lobes):
        values = table.values[row, thickness_index]   # (n_ti, n_to, n_phi, C)
        errors = table.stderr[row, thickness_index]
        for col, c in enumerate(shown):
            ax = axes[row, col]
            for colour, i in zip(colours, incidences):
                x, f = in_plane(values[i, :, :, c], deg_o)
                _, e = in_plane(errors[i, :, :, c], deg_o)
                ax.plot(x, f, color=colour, lw=1.2, label=f"theta_i {deg_i[i]:.1f} deg")
                ax.fill_between(x, f - width * e, f + width * e, color=colour, alpha=0.25, lw=0)
            ax.axvline(0, color="0.6", lw=0.6)
            ax.set_xlim(-90, 90)
            ax.set_xlabel("theta_o [deg]  (< 0: phi = 0, back;  > 0: phi = 180, mirror side)", fontsize=8)
            ax.set_ylabel("f [1/sr]")
            ax.set_title(f"{lobe}, {_channel_label(table, c)}", fontsize=10)
            ax.grid(alpha=0.3)
            if col == 0:
                ax.legend(fontsize=7)
        _error_map(fig, axes[row, -1], table, values, errors, lobe, deg_i, deg_o, deg_phi, kind)
    thickness = (f", film {g.thickness_nm[thickness_index]:g} nm" if g.thickness_nm else "")
    model = table.model.get("type", "model")
    part = ("\nthe scattered part only: the top interface's own reflection (its specular peak included) is "
            "added exactly at lookup" + (" (from below: the base's)" if table.two_sided else "")
            if table.split_direct else "")
    parts = f"\nparts (rows): {', '.join(table.lobes)}"
    fig.suptitle(f"{source}{model} table{thickness}: {band}{part}{parts}", fontsize=11)
    save_figure(fig, path)
    plt.close(fig)
    return f"{band}{part}{parts}".replace("\n", "; ")


def _error_map(fig, ax, table, values, errors, lobe, deg_i, deg_o, deg_phi, kind) -> None:
    """Worst channel's relative error (``kind``: standard error or bound) over theta_o x phi
    at the middle theta_i."""
    i = len(deg_i) // 2
    floor = SIGNIFICANT * max(float(table.values.max(initial=0.0)), 1e-300)
    f, e = values[i].astype(np.float64), errors[i].astype(np.float64)
    significant = f > floor
    worst = np.where(significant, e / np.where(significant, f, 1.0), -np.inf).max(axis=-1)
    rel = np.where(np.isfinite(worst), worst, np.nan)  # NaN: blank pixel
    half_step = 0.5 * (deg_phi[1] - deg_phi[0])  # phi nodes include both ends; theta_o are cell centres
    image = ax.imshow(100 * rel, origin="lower", aspect="auto", cmap="magma",
                      extent=(deg_phi[0] - half_step, deg_phi[-1] + half_step, 0, 90))
    fig.colorbar(image, ax=ax, label=f"relative {'error bound' if kind == BOUND else 'standard error'} [%]")
    ax.set_xticks([0, 45, 90, 135, 180])
    ax.set_xlabel("phi = |phi_o - phi_i| [deg]")
    ax.set_ylabel("theta_o [deg]")
    ax.set_title(f"{lobe} error at theta_i {deg_i[i]:.1f} deg (worst channel)", fontsize=10)
