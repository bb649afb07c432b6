"""Top-down drawing of the room, its obstacles and the reflectors (matplotlib)."""

from __future__ import annotations

TYPE_COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def draw_room(ax, world, *, marker_size: float = 90.0) -> None:
    """Room outline, obstacle footprints (grey) and reflectors (one colour per type)."""
    from matplotlib.patches import Rectangle

    lx, ly = world.room.size_m[:2]
    ax.add_patch(Rectangle((0, 0), lx, ly, fill=False, lw=2, color="black"))
    for box in world.room.obstacles:
        ax.add_patch(Rectangle(box.min_m[:2], *(box.max_m[:2] - box.min_m[:2]), color="0.6"))
    layout = world.layout
    for t, rtype in enumerate(layout.types):
        sel = layout.type_index == t
        ax.scatter(
            *layout.positions_m[sel, :2].T,
            marker="X",
            s=marker_size,
            zorder=5,
            color=TYPE_COLOURS[t % len(TYPE_COLOURS)],
            label=f"LRP type {rtype.name}",
        )
