"""Top-down rendering of the env with matplotlib (Agg for ``rgb_array``, a window for ``human``)."""

from __future__ import annotations

import numpy as np

from lrp_gym.world.plotting import TYPE_COLOURS, draw_room


def covariance_ellipse(cov_xy: np.ndarray, n_sigma: float = 2.0, n_points: int = 48) -> np.ndarray:
    """Outline (n_points, 2) of the ``n_sigma`` ellipse of a 2x2 covariance, centred at 0."""
    vals, vecs = np.linalg.eigh(0.5 * (cov_xy + cov_xy.T))
    radii = n_sigma * np.sqrt(np.clip(vals, 0.0, None))
    t = np.linspace(0, 2 * np.pi, n_points)
    return (vecs @ (radii[:, None] * np.stack([np.cos(t), np.sin(t)]))).T


class Renderer:
    """Draws room, obstacles, reflectors, path, true and estimated pose, particles, ranges."""

    def __init__(self, world, size_px: int, mode: str) -> None:
        import matplotlib

        if mode == "rgb_array":
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            self.fig = Figure(figsize=(size_px / 100, size_px / 100), dpi=100)
            FigureCanvasAgg(self.fig)
        else:
            import matplotlib.pyplot as plt

            if matplotlib.get_backend().lower() == "agg":
                import gymnasium as gym

                gym.logger.warn(
                    "render_mode='human' needs a display; the Agg backend draws off-screen"
                )
            plt.ion()
            self.fig = plt.figure(figsize=(size_px / 100, size_px / 100), dpi=100)
        self.mode = mode
        self.world = world
        self.ax = self.fig.add_axes((0.1, 0.22, 0.86, 0.72))  # room for the legend below

    def draw(self, env):
        """Paint one frame of ``env``, layer by layer; the RGB array in ``rgb_array`` mode."""
        ax, world = self.ax, self.world
        lx, ly = world.room.size_m[:2]
        ax.clear()
        ax.set_xlim(-0.1, lx + 0.1)
        ax.set_ylim(-0.1, ly + 0.1)
        ax.set_aspect("equal")
        draw_room(ax, world)
        self._draw_path(env.path)
        self._draw_particles(getattr(env.localizer, "particles", None))
        if env.fingerprint is not None:
            self._draw_range_circles(env.fingerprint, env.pose)
        self._draw_true_pose(env.pose)
        if env.estimate is not None:
            self._draw_estimate(env.estimate)
        self._draw_labels(env)
        return self._show()

    def _draw_path(self, path) -> None:
        """Waypoints as a dashed polyline and the goal as a star."""
        waypoints = path.waypoints_m
        self.ax.plot(waypoints[:, 0], waypoints[:, 1], "--", color="0.4", lw=1)
        self.ax.scatter(waypoints[:, 0], waypoints[:, 1], s=10, color="0.4")
        goal = path.goal_m
        self.ax.scatter(goal[0], goal[1], marker="*", s=200, color="gold", edgecolor="k", zorder=6)

    def _draw_particles(self, particles: np.ndarray | None) -> None:
        """At most ~1500 particles (every k-th), so a 10 000-particle cloud draws quickly."""
        if particles is None or not len(particles):
            return
        step = max(len(particles) // 1500, 1)
        self.ax.scatter(
            particles[::step, 0], particles[::step, 1], s=1, color="tab:orange", alpha=0.4
        )

    def _draw_range_circles(self, fingerprint, pose: np.ndarray) -> None:
        """Tracked distances as floor-plane circles around the reflector they best fit."""
        world, layout = self.world, self.world.layout
        radar = world.radar_position(pose[:2])
        dz2 = (layout.positions_m[:, 2] - world.mount_height_m) ** 2
        for t, dists in enumerate(fingerprint.distances_m):
            idx = np.flatnonzero(layout.type_index == t)
            true_d = layout.distances_m(radar)[idx]
            for d in dists:
                j = idx[np.argmin(np.abs(true_d - d))]
                # The slant distance projected onto the floor plane of the radar.
                r = np.sqrt(max(d**2 - dz2[j], 0.0))
                circ = np.linspace(0, 2 * np.pi, 90)
                self.ax.plot(
                    layout.positions_m[j, 0] + r * np.cos(circ),
                    layout.positions_m[j, 1] + r * np.sin(circ),
                    color=TYPE_COLOURS[t % len(TYPE_COLOURS)],
                    lw=0.6,
                    alpha=0.5,
                )

    def _draw_true_pose(self, pose: np.ndarray) -> None:
        """The robot's outline and heading arrow at its true pose."""
        x, y, th = pose
        self.ax.add_patch(plt_circle((x, y), self.world.robot.radius_m, "tab:green"))
        self.ax.arrow(
            x, y, 0.35 * np.cos(th), 0.35 * np.sin(th), width=0.02, color="tab:green", zorder=7
        )

    def _draw_estimate(self, est) -> None:
        """The estimated pose's 2-sigma position ellipse and heading arrow."""
        ex, ey, eth = est.pose
        ell = covariance_ellipse(est.covariance[:2, :2]) + est.pose[:2]
        self.ax.plot(ell[:, 0], ell[:, 1], color="tab:purple", lw=1.5)
        self.ax.arrow(
            ex,
            ey,
            0.3 * np.cos(eth),
            0.3 * np.sin(eth),
            width=0.015,
            color="tab:purple",
            zorder=8,
        )

    def _draw_labels(self, env) -> None:
        """Title (step, position error, detections), axis labels and the legend below."""
        ax, est = self.ax, env.estimate
        err = float(np.hypot(*(est.pose[:2] - env.pose[:2]))) if est is not None else float("nan")
        ax.set_title(
            f"step {env._steps}  error {err:.3f} m  dets {len(env.detections)}", fontsize=9
        )
        ax.set_xlabel("x [m]", fontsize=8)
        ax.set_ylabel("y [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        own = ax.get_legend_handles_labels()[0]  # the LRP types, from draw_room
        ax.legend(
            handles=[*own, *legend_handles()],
            loc="upper center",
            bbox_to_anchor=(0.5, -0.1),
            ncol=3,
            fontsize=6,
            frameon=False,
        )

    def _show(self):
        """Render the canvas: the RGB array (H, W, 3) in ``rgb_array`` mode, else a window."""
        self.fig.canvas.draw()
        if self.mode == "rgb_array":
            buf = np.asarray(self.fig.canvas.buffer_rgba())
            return np.ascontiguousarray(buf[..., :3])
        import matplotlib.pyplot as plt

        plt.pause(1.0 / 30)
        return None

    def close(self) -> None:
        if self.mode == "human":
            import matplotlib.pyplot as plt

            plt.close(self.fig)


def legend_handles() -> list:
    """Proxy artists for every layer draw() paints (arrows and clouds have no legend look)."""
    from matplotlib.lines import Line2D

    return [
        Line2D([], [], marker="o", mfc="none", color="tab:green", ls="-", label="true pose"),
        Line2D([], [], color="tab:purple", lw=1.5, label="estimate, 2-sigma ellipse"),
        Line2D([], [], marker=".", color="tab:orange", ls="none", alpha=0.6, label="particles"),
        Line2D([], [], color=TYPE_COLOURS[0], lw=0.8, label="tracked range circles"),
        Line2D([], [], color="0.4", ls="--", marker=".", label="path"),
        Line2D([], [], marker="*", color="gold", mec="k", ms=10, ls="none", label="goal"),
    ]


def plt_circle(centre, radius, colour):
    from matplotlib.patches import Circle

    return Circle(centre, radius, fill=False, color=colour, lw=1.5, zorder=7)
