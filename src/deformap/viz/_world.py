"""Pictures of a world for a person to check it: layout, the camera's colour view, one observed
cloud, one dent (here, not in :mod:`deformap.world`, which never imports matplotlib)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.patches import Polygon, Rectangle
from matplotlib.ticker import NullLocator

from deformap.viz._save import save_figure
from deformap.viz._style import RIGID_COLOUR, STIFFNESS_CMAP, modulus_norm
from deformap.world import CAMERA_PRESETS, youngs_modulus_to_hardness

if TYPE_CHECKING:
    from deformap.world import SimulatedWorld

__all__ = ["show_world"]


def _press_target(world: SimulatedWorld) -> np.ndarray:
    """The centroid of the softest foam block (the clearest dent)."""
    foams = [b for b in world.regions if not b.rigid]
    if not foams:
        return np.asarray(world.workspace.center)
    soft = min(foams, key=lambda b: b.modulus_pa)
    return np.asarray(soft.polygon.mean(axis=0))


def show_world(world: SimulatedWorld, out: str | Path, *, force_n: float) -> list[Path]:
    """Write ``layout.png``, ``rgb.png``, ``cloud.png`` and ``dent.png`` into the folder ``out``
    (created if needed); returns their paths.

    ``layout.png`` colours each foam block by its stiffness (:mod:`deformap.viz._style`) with a
    colour bar in Young's modulus and hardness, rigid blocks grey; ``rgb.png`` shows the camera's
    colour image and one observation's coloured cloud from above; ``cloud.png`` one observation
    by height; ``dent.png`` presses the centroid of the softest foam block once with ``force_n``
    newtons and releases it.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures = (("layout", _layout_figure), ("rgb", _rgb_figure), ("cloud", _cloud_figure),
               ("dent", lambda w: _dent_figure(w, force_n)))  # fmt: skip
    return [save_figure(draw(world), out / f"{name}.png", dpi=120, bbox_inches="tight")
            for name, draw in figures]


def _layout_figure(world: SimulatedWorld) -> Figure:
    """The blocks coloured by E on a log scale (rigid grey), named with hardness, E and
    thickness; the workspace and where the camera stands."""
    fig = Figure(figsize=(7.5, 5), layout="constrained")
    ax = fig.subplots()
    foams = [b for b in world.regions if not b.rigid]
    norm = modulus_norm([b.modulus_pa / 1e3 for b in foams])
    cmap = colormaps[STIFFNESS_CMAP]
    for b in world.regions:
        colour = RIGID_COLOUR if b.rigid else cmap(norm(b.modulus_pa / 1e3))
        ax.add_patch(Polygon(b.polygon, closed=True, facecolor=colour, edgecolor="k",
                             hatch="//" if b.rigid else None))  # fmt: skip
        cx, cy = b.polygon.mean(axis=0)
        lines = [b.name]
        if b.rigid:
            lines += [] if b.name == "rigid" else ["rigid"]  # the name may say it already
        else:
            lines += [f"{b.hardness:.0f} N, E = {b.modulus_pa / 1e3:.1f} kPa"]
        ax.text(cx, cy, "\n".join([*lines, f"t = {b.thickness_m * 100:.0f} cm"]), ha="center",
                va="center", fontsize=9,
                bbox={"boxstyle": "round,pad=0.2", "fc": "w", "ec": "none", "alpha": 0.8})
    if foams:  # ticks at the blocks' own values: E on the right, hardness on the left
        bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.8,
                           label="Young's modulus E [kPa] (log scale)")  # fmt: skip
        moduli = sorted({round(b.modulus_pa / 1e3, 1) for b in foams})
        bar.set_ticks(moduli, labels=[f"{e:g}" for e in moduli])
        bar.ax.yaxis.set_minor_locator(NullLocator())
        per_kpa = youngs_modulus_to_hardness(1e3)  # hardness is proportional to E
        side = bar.ax.secondary_yaxis("left", functions=(
            lambda e: np.asarray(e) * per_kpa, lambda h: np.asarray(h) / per_kpa))
        hardness = sorted({round(b.hardness, 1) for b in foams})
        side.set_yticks(hardness, labels=[f"{h:g}" for h in hardness])
        side.yaxis.set_minor_locator(NullLocator())
        side.set_ylabel("hardness H [N]")
    (x0, y0), (w, d) = world.workspace.lower, world.workspace.size
    ax.add_patch(Rectangle((x0, y0), w, d, fill=False, linestyle="--", edgecolor="b"))
    cam = world.camera.origin
    ax.annotate("camera", xy=(cam[0], y0), xytext=(cam[0], y0 - 0.06), ha="center",
                arrowprops={"arrowstyle": "->"})
    ax.set(xlim=(x0 - 0.05, x0 + w + 0.05), ylim=(y0 - 0.08, y0 + d + 0.05), aspect="equal",
           xlabel="x [m]", ylabel="y [m]", title=f"{world.scenario.name}: layout and stiffness")
    return fig


def _camera_name(world: SimulatedWorld) -> str:
    """The preset whose configuration the world's camera has, else its resolution."""
    config = world.camera.config
    for name, make in CAMERA_PRESETS.items():
        if make() == config:
            return name
    return f"custom camera {config.width}×{config.height}"


def _rgb_figure(world: SimulatedWorld) -> Figure:
    """The camera's colour image as it sees the scene (no-return pixels white), and one observed
    cloud from above in world metres, each point drawn in its own colour."""
    image = world.rgb_image()
    cloud = world.observe()
    fig = Figure(figsize=(13, 4.8), layout="constrained")
    a1, a2 = fig.subplots(1, 2)
    a1.imshow(np.nan_to_num(image, nan=1.0), interpolation="nearest")
    a1.set(xlabel="image column [px]", ylabel="image row [px]",
           title=f"{world.scenario.name}: {_camera_name(world)} colour view")
    step = max(1, len(cloud) // 60000)
    colours = cloud.colors if cloud.colors is not None else np.full((len(cloud), 3), 0.5)
    a2.scatter(cloud.xy[::step, 0], cloud.xy[::step, 1], c=np.clip(colours[::step], 0, 1),
               s=2.0, linewidths=0)  # points large enough that their colour reads
    a2.set(aspect="equal", xlabel="x [m]", ylabel="y [m]",
           title=f"coloured cloud from above, {len(cloud)} points")
    return fig


def _cloud_figure(world: SimulatedWorld) -> Figure:
    """One observed cloud from above, coloured by height, and a side view of a band of it."""
    cloud = world.observe()
    # wspace: the colour bar's label apart from the next panel's y label
    fig = Figure(figsize=(12, 4.5), layout=ConstrainedLayoutEngine(wspace=0.08))
    a1, a2 = fig.subplots(1, 2)
    step = max(1, len(cloud) // 60000)
    sc = a1.scatter(cloud.xy[::step, 0], cloud.xy[::step, 1], c=cloud.z[::step], s=0.3,
                    cmap="viridis", vmin=-0.01, vmax=0.07)
    fig.colorbar(sc, ax=a1, label="z [m]")
    a1.set(aspect="equal", xlabel="x [m]", ylabel="y [m]",
           title=f"observed cloud, {len(cloud)} points "
                 f"({int(world.workspace.contains(cloud.xy).sum())} on the area)")
    band = np.abs(cloud.xy[:, 0] - world.workspace.center[0]) < 0.01
    a2.scatter(cloud.xy[band, 1], cloud.z[band], s=0.5)
    a2.set(xlabel="y [m]", ylabel="z [m]", title="side view of a 2 cm band at the centre x")
    return fig


def _dent_figure(world: SimulatedWorld, force: float) -> Figure:
    """The surface before and pressed on one height scale, and a section through the press with
    the tip and the cloud; every length in millimetres."""
    target = _press_target(world)
    obs = world.press(target, force)
    dent = world.dent(target, force)
    world.release()
    xs = np.linspace(target[0] - 0.06, target[0] + 0.06, 121)
    ys = np.linspace(target[1] - 0.06, target[1] + 0.06, 121)
    before = world.surface_height(xs, ys)
    after = world.surface_height(xs, ys, dent.displacement)
    mm = 1e3
    fig = Figure(figsize=(16, 4.5), layout="constrained")
    # the section wider: drawn to scale (equal aspect), it is short and needs the width
    axes = fig.subplots(1, 3, width_ratios=(1.0, 1.0, 1.4))
    ext = (xs[0] * mm, xs[-1] * mm, ys[0] * mm, ys[-1] * mm)
    panels = ((axes[0], before, "surface before"), (axes[1], after, "surface pressed"))
    for ax, img, title in panels:
        im = ax.imshow(img * mm, origin="lower", extent=ext, cmap="viridis",
                       vmin=after.min() * mm, vmax=before.max() * mm)
        ax.set(title=title, xlabel="x [mm]", ylabel="y [mm]")
        fig.colorbar(im, ax=ax, label="z [mm]")
    ax = axes[2]
    row = np.argmin(np.abs(ys - target[1]))
    ax.plot(xs * mm, before[row] * mm, label="before (FEM)")
    ax.plot(xs * mm, after[row] * mm, label="pressed (FEM)")
    pts = obs.cloud.points
    band = (np.abs(pts[:, 1] - target[1]) < 0.003) & (np.abs(pts[:, 0] - target[0]) < 0.06)
    ax.scatter(pts[band, 0] * mm, pts[band, 2] * mm, s=3, c="gray",
               label="pressed cloud (±3 mm)")  # fmt: skip
    tip = obs.contact.tip_center
    theta = np.linspace(0, 2 * np.pi, 100)
    r = obs.contact.tip_radius_m
    ax.plot((tip[0] + r * np.cos(theta)) * mm, (tip[2] + r * np.sin(theta)) * mm, "k",
            label="tip")
    ax.set_aspect("equal")
    # the middle half of the section (the dent and its rim): to scale, the whole 12 cm would
    # leave the panel a sliver
    ax.set(xlabel="x [mm]", ylabel="z [mm]", ylim=(after.min() * mm - 5, before.max() * mm + 25),
           xlim=((target[0] - 0.03) * mm, (target[0] + 0.03) * mm),
           title=f"section: {force:.2f} N at x = {target[0] * mm:.0f} mm, "
                 f"y = {target[1] * mm:.0f} mm\n"
                 f"dent {dent.depth_m * mm:.1f} mm, contact radius a = "
                 f"{dent.contact_radius_m * mm:.1f} mm")
    # beside the axes: inside, the legend would cover the tip (the equal aspect leaves the panel short)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    return fig
