"""Ambiguity map figure: areas sharing fingerprints coloured by group, unique areas white."""

from __future__ import annotations

import numpy as np

from lrp_gym.placement.ambiguity import AmbiguityResult
from lrp_gym.placement.scenario import layout_arrays

_MARKERS = ("o", "s", "^", "D", "v", "P")


def plot_ambiguity_map(
    result: AmbiguityResult,
    room_size_m: np.ndarray,
    reflectors_m: np.ndarray,
    type_index: np.ndarray,
    type_names: tuple[str, ...],
    *,
    obstacles: list[tuple[np.ndarray, np.ndarray]] | None = None,
    path_xy_m: np.ndarray | None = None,
    title: str = "",
):
    """Draw the ambiguity map; return the matplotlib figure (Agg backend, not shown).

    Parameters
    ----------
    result : AmbiguityResult
    room_size_m : array, shape (>= 2,)
    reflectors_m : ndarray, shape (M, 3)
    type_index : ndarray of int, shape (M,)
    type_names : tuple of str
    obstacles : list of (min_m, max_m), optional
        Obstacle boxes, shaded grey.
    path_xy_m : ndarray, shape (K, 2), optional
        The task path, drawn with numbered waypoints (1-based).
    title : str
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.legend_handler import HandlerTuple
    from matplotlib.patches import Rectangle

    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    lx, ly = float(room_size_m[0]), float(room_size_m[1])
    im, cmap, excluded = _draw_groups(ax, result)
    _draw_obstacles(ax, obstacles or [])
    ax.add_patch(Rectangle((0, 0), lx, ly, fill=False, edgecolor="k", linewidth=2, zorder=4))
    if path_xy_m is not None and len(path_xy_m):
        _draw_path(ax, np.asarray(path_xy_m, dtype=float))
    handles, labels = _area_legend(result, cmap, excluded, path_xy_m is not None)
    _draw_reflectors(ax, reflectors_m, type_index, type_names, handles, labels)
    _label_axes(ax, result, lx, ly, title)
    ax.legend(
        handles,
        labels,
        handler_map={tuple: HandlerTuple(ndivide=1)},
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        fontsize=8,
        frameon=False,
    )
    if result.n_groups:
        bar = fig.colorbar(im, ax=ax, fraction=0.04, pad=0.1, location="bottom", aspect=40)
        bar.set_label(
            f"ambiguity group: cells of one colour share a fingerprint ({result.n_groups} groups)",
            fontsize=8,
        )
        bar.set_ticks([])
    return fig


def _label_axes(ax, result: AmbiguityResult, lx: float, ly: float, title: str) -> None:
    """Room limits with a 5 % margin, equal aspect, axis labels; the title defaults to the
    ambiguous fractions."""
    ax.set_xlim(-0.05 * lx, 1.05 * lx)
    ax.set_ylim(-0.05 * ly, 1.05 * ly)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(
        title
        or f"ambiguous {100 * result.ambiguous_fraction:.1f} % "
        f"(systematic {100 * result.systematic_fraction:.1f} %, "
        f"random {100 * result.random_fraction:.1f} %)",
        fontsize=10,
    )


def _draw_groups(ax, result: AmbiguityResult):
    """Ambiguity groups one colour each (unique cells white), cells not analysed light grey.

    Returns the group image (for the colour bar), its colour map and whether any cell was
    left out of the analysis.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    grid = result.grid
    img = grid.to_image(result.group.astype(float), fill=np.nan)
    img[img < 0] = np.nan  # unique cells: white background
    n = max(result.n_groups, 1)
    base = plt.get_cmap("tab20")(np.arange(20) % 20)
    cmap = ListedColormap(base[np.arange(n) % 20]).with_extremes(bad="white")
    im = ax.imshow(
        np.ma.masked_invalid(img),
        origin="lower",
        extent=grid.extent(),
        cmap=cmap,
        vmin=-0.5,
        vmax=n - 0.5,
        interpolation="nearest",
    )
    excluded = np.isnan(grid.to_image(np.zeros(len(grid)), fill=np.nan))
    if excluded.any():
        ax.imshow(
            np.ma.masked_where(~excluded, excluded.astype(float)),
            origin="lower",
            extent=grid.extent(),
            cmap=ListedColormap(["0.85"]),
            interpolation="nearest",
        )
    return im, cmap, bool(excluded.any())


def _draw_obstacles(ax, obstacles: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """Obstacle boxes (min_m, max_m) as hatched grey rectangles."""
    from matplotlib.patches import Rectangle

    for lo, hi in obstacles:
        ax.add_patch(
            Rectangle(
                (float(lo[0]), float(lo[1])),
                hi[0] - lo[0],
                hi[1] - lo[1],
                facecolor="0.55",
                edgecolor="k",
                hatch="//",
                alpha=0.8,
                zorder=3,
            )
        )


def _draw_path(ax, path: np.ndarray) -> None:
    """The task path (K, 2) as a black polyline with its waypoints numbered from 1."""
    ax.plot(path[:, 0], path[:, 1], "-", color="k", linewidth=1.2, zorder=5)
    ax.plot(path[:, 0], path[:, 1], "o", color="k", markersize=3, zorder=5)
    for k, (x, y) in enumerate(path, start=1):
        ax.annotate(str(k), (x, y), textcoords="offset points", xytext=(3, 3), fontsize=7, zorder=6)


def _draw_reflectors(
    ax,
    reflectors_m: np.ndarray,
    type_index: np.ndarray,
    type_names: tuple[str, ...],
    handles: list,
    labels: list[str],
) -> None:
    """Each type's reflectors as a white marker with a black x; appends their legend entries."""
    from matplotlib.lines import Line2D

    refl = np.asarray(reflectors_m, dtype=float)
    for t, name in enumerate(type_names):
        sel = np.asarray(type_index) == t
        if not sel.any():
            continue
        marker = _MARKERS[t % len(_MARKERS)]
        ax.scatter(
            refl[sel, 0],
            refl[sel, 1],
            marker=marker,
            s=90,
            facecolor="white",
            edgecolor="k",
            linewidth=1.8,
            zorder=7,
            label=f"LRP type {name}",
        )
        ax.scatter(refl[sel, 0], refl[sel, 1], marker="x", s=40, color="k", zorder=8)
        # The legend shows the same marker as the map: white shape with a black x.
        shape = Line2D([], [], marker=marker, ls="none", ms=9, mfc="white", mec="k", mew=1.8)
        handles.append((shape, Line2D([], [], marker="x", ls="none", ms=6, color="k")))
        labels.append(f"LRP type {name}")


def _area_legend(result: AmbiguityResult, cmap, excluded: bool, path: bool):
    """Legend entries for the map's areas (the LRP markers are added by the caller)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list = [Patch(facecolor="white", edgecolor="0.5")]
    labels = ["unique fingerprint"]
    if result.n_groups:
        handles.append(Patch(color=cmap(0)))
        labels.append("ambiguous (colour = group, bar below)")
    if excluded:
        handles.append(Patch(facecolor="0.85"))
        labels.append("not analysed (obstacle, wall clearance)")
    if path:
        handles.append(Line2D([], [], color="k", marker="o", ms=3, lw=1.2))
        labels.append("task path (numbered waypoints)")
    return handles, labels


def plot_scenario_map(cfg, result: AmbiguityResult, title: str = ""):
    """:func:`plot_ambiguity_map` for a scenario (room, obstacles, layout and task path)."""
    pos, idx, names = layout_arrays(cfg)
    return plot_ambiguity_map(
        result,
        np.asarray(cfg.room.size),
        pos,
        idx,
        names,
        obstacles=[(np.asarray(b.min), np.asarray(b.max)) for b in cfg.room.obstacles],
        path_xy_m=np.asarray(cfg.task.path) if cfg.task.path else None,
        title=title,
    )
