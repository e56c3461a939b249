"""Animation and trajectory plots of planar mechanisms, read from a simulation log.

The drawing is found in the log itself, by instance path: a *frame* is any ``P`` with
``P.x``, ``P.y``, ``P.phi`` and ``P.fx`` logged (a multibody :class:`Frame`). Frames are
grouped by their component (the path without the last part):

- a component with two frames is a *link* drawn as a segment between them (a joint, whose
  frames coincide, as a small circle; a line-force element, recognised by its ``L`` and
  ``f`` variables, as a thin dashed line);
- a component with one frame and an ``E_kin`` variable is a *mass* drawn as a dot (at its
  centre of mass ``x``, ``y`` when it logs one, with a line to its frame);
- a component with one frame that never moves is *ground*, drawn as a triangle.

No window is opened: figures are built without ``pyplot``. GIF files are written with
Pillow (always available with matplotlib); MP4 needs the ``ffmpeg`` program on the PATH.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechatron._io import atomic_path, save_figure
from mechatron.errors import DataError, MechatronError

__all__ = ["animate", "plot_trajectories", "find_mechanism", "Mechanism",
           "VisualizationError"]


class VisualizationError(MechatronError, RuntimeError):
    """An animation or plot cannot be made (nothing to draw, a missing writer)."""


@dataclass
class Mechanism:
    """What :func:`find_mechanism` found in a log: instance paths of frames, grouped."""

    links: list[tuple[str, str, str]] = field(default_factory=list)   # (comp, a, b)
    joints: list[str] = field(default_factory=list)                   # frame paths
    line_forces: list[tuple[str, str, str]] = field(default_factory=list)
    masses: list[tuple[str, str, str | None]] = field(default_factory=list)
    # (comp, frame, centre-of-mass prefix or None)
    ground: list[str] = field(default_factory=list)                   # frame paths

    def points(self) -> list[str]:
        """Every frame path drawn (for the axis limits)."""
        out = [p for _, a, b in self.links for p in (a, b)]
        out += self.joints + self.ground + [f for _, f, _ in self.masses]
        out += [p for _, a, b in self.line_forces for p in (a, b)]
        return out


def _frames(res) -> list[str]:
    names = set(res.names)
    out = []
    for n in res.names:
        if n.endswith(".fx"):
            p = n[:-3]
            if {f"{p}.x", f"{p}.y", f"{p}.phi"} <= names:
                out.append(p)
    return out


def find_mechanism(res) -> Mechanism:
    """Group the frames of a log into links, joints, masses and ground (module doc).

    Raises
    ------
    VisualizationError
        If the log holds no multibody frame.
    """
    frames = _frames(res)
    if not frames:
        raise VisualizationError(
            f"{_where(res)}: no multibody frame in the log (no variables 'P.x', 'P.y', "
            "'P.phi', 'P.fx'). Animate a model built from mechatron.library.multibody.",
            path=res.model_name or None)
    names = set(res.names)
    by_comp: dict[str, list[str]] = {}
    for f in frames:
        comp = f.rsplit(".", 1)[0] if "." in f else ""
        by_comp.setdefault(comp, []).append(f)
    mech = Mechanism()
    for comp, fs in by_comp.items():
        if len(fs) == 2:
            a, b = sorted(fs)
            if f"{comp}.L" in names and f"{comp}.f" in names:
                mech.line_forces.append((comp, a, b))
                continue
            gap = np.hypot(res[f"{a}.x"] - res[f"{b}.x"], res[f"{a}.y"] - res[f"{b}.y"])
            if np.max(gap) < 1e-9:
                mech.joints.append(a)
            else:
                mech.links.append((comp, a, b))
        elif len(fs) == 1:
            f = fs[0]
            if f"{comp}.E_kin" in names:
                com = comp if {f"{comp}.x", f"{comp}.y"} <= names else None
                mech.masses.append((comp, f, com))
            elif np.ptp(res[f"{f}.x"]) == 0 and np.ptp(res[f"{f}.y"]) == 0 \
                    and np.ptp(res[f"{f}.phi"]) == 0 and not comp.endswith("sensor"):
                mech.ground.append(f)
    return mech


def _where(res) -> str:
    return f"simlog of {res.model_name!r}" if res.model_name else "simlog"


def _limits(res, mech: Mechanism, margin: float = 0.1):
    xs = [res[f"{p}.x"] for p in mech.points()]
    ys = [res[f"{p}.y"] for p in mech.points()]
    xs += [res[f"{c}.x"] for _, _, c in mech.masses if c]
    ys += [res[f"{c}.y"] for _, _, c in mech.masses if c]
    x0, x1 = min(map(np.min, xs)), max(map(np.max, xs))
    y0, y1 = min(map(np.min, ys)), max(map(np.max, ys))
    span = max(x1 - x0, y1 - y0, 1e-3)
    pad = margin * span
    return (x0 - pad, x1 + pad), (y0 - pad, y1 + pad)


def animate(res, path: str | os.PathLike[str], *, fps: float = 25.0, speed: float = 1.0,
            max_frames: int = 400, trace: bool = True, dpi: int = 80,
            title: str | None = None) -> Path:
    """Write an animation of the mechanism in a simulation log.

    Parameters
    ----------
    res : SimResult
        Log of a model built from multibody parts (see the module doc for what is drawn).
    path : str or path-like
        Destination ending in ``.gif`` (Pillow) or ``.mp4`` (needs ``ffmpeg``).
    fps : float
        Frames per second of the file.
    speed : float
        Simulated seconds per second of animation (1 = real time).
    max_frames : int
        Upper bound on the number of frames (the time step grows to respect it).
    trace : bool
        Draw the path travelled by each mass.
    dpi : int
        Resolution of the frames.
    title : str, optional
        Figure title (default: the model name).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    VisualizationError
        If the log holds no frame, the suffix is unknown, or MP4 is asked without
        ``ffmpeg`` on the PATH.
    DataError
        If ``fps``, ``speed`` or ``max_frames`` are not positive.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise VisualizationError(f"animate: cannot write '{path}': the suffix must be .gif "
                                 "or .mp4.", path=str(path))
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise VisualizationError(
            f"animate: cannot write '{path}': MP4 needs the ffmpeg program, which is not "
            "on the PATH. Install ffmpeg (e.g. apt-get install ffmpeg) or write a .gif.",
            path=str(path))
    if not (fps > 0 and speed > 0 and max_frames > 0):
        raise DataError(f"animate: fps, speed and max_frames must be > 0, got fps={fps!r}, "
                        f"speed={speed!r}, max_frames={max_frames!r}.")
    mech = find_mechanism(res)
    t = np.asarray(res.t, dtype=float)
    duration = (t[-1] - t[0]) / speed
    n = int(min(max_frames, max(2, round(duration * fps) + 1)))
    times = np.linspace(t[0], t[-1], n)

    def at(name):
        return np.interp(times, t, res[name])

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5.0, 5.0))
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.14, 0.1, 0.82, 0.82))
    (xl, yl) = _limits(res, mech)
    ax.set_xlim(*xl)
    ax.set_ylim(*yl)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title if title is not None else (res.model_name or "mechanism"))
    for g in mech.ground:
        ax.plot(res[f"{g}.x"][0], res[f"{g}.y"][0], marker="^", color="0.3", markersize=11,
                linestyle="none")

    def artist(*args, **kw):
        return ax.plot([], [], *args, animated=True, **kw)[0]

    links = [(artist("-", color="#4060a0", lw=3, solid_capstyle="round"),
              at(f"{a}.x"), at(f"{a}.y"), at(f"{b}.x"), at(f"{b}.y"))
             for _, a, b in mech.links]
    springs = [(artist("--", color="#b05020", lw=1.2),
                at(f"{a}.x"), at(f"{a}.y"), at(f"{b}.x"), at(f"{b}.y"))
               for _, a, b in mech.line_forces]
    joints = [(artist("o", mfc="white", mec="k", ms=7), at(f"{j}.x"), at(f"{j}.y"))
              for j in mech.joints]
    masses = []
    for comp, f, com in mech.masses:
        px, py = (at(f"{com}.x"), at(f"{com}.y")) if com else (at(f"{f}.x"), at(f"{f}.y"))
        tr = artist("-", color="#c03030", lw=0.6, alpha=0.5) if trace else None
        arm = artist("-", color="#c03030", lw=1.5) if com else None
        dot = artist("o", color="#c03030", ms=10)
        full = (res[f"{com or f}.x"], res[f"{com or f}.y"])
        masses.append((dot, arm, tr, px, py, at(f"{f}.x"), at(f"{f}.y"), full))
    clock = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top", animated=True)
    upto = np.searchsorted(t, times, side="right")   # the trace at the log's resolution

    def draw(k):
        artists = []
        for dot, arm, tr, px, py, fx, fy, (hx, hy) in masses:
            if tr is not None:
                tr.set_data(np.append(hx[:upto[k]], px[k]), np.append(hy[:upto[k]], py[k]))
                artists.append(tr)
        for line, ax_, ay_, bx_, by_ in links + springs:
            line.set_data([ax_[k], bx_[k]], [ay_[k], by_[k]])
            artists.append(line)
        for mk, jx, jy in joints:
            mk.set_data([jx[k]], [jy[k]])
            artists.append(mk)
        for dot, arm, tr, px, py, fx, fy, _ in masses:
            if arm is not None:
                arm.set_data([fx[k], px[k]], [fy[k], py[k]])
                artists.append(arm)
            dot.set_data([px[k]], [py[k]])
            artists.append(dot)
        clock.set_text(f"t = {times[k]:.2f} s")
        artists.append(clock)
        return artists

    fig.set_dpi(dpi)
    canvas.draw()                                   # the static part, once
    background = canvas.copy_from_bbox(fig.bbox)
    path.parent.mkdir(parents=True, exist_ok=True)
    frames = []
    for k in range(n):                              # then only the moving artists
        canvas.restore_region(background)
        for a in draw(k):
            ax.draw_artist(a)
        frames.append(np.asarray(canvas.buffer_rgba()).copy())
    if suffix == ".gif":
        _write_gif(frames, path, fps)
    else:
        _write_mp4(frames, path, fps)
    return path


def _write_gif(frames, path: Path, fps: float) -> None:
    from PIL import Image

    images = [Image.fromarray(f[..., :3]) for f in frames]
    palette = images[0].quantize(colors=64)
    images = [im.quantize(palette=palette) for im in images]
    with atomic_path(path) as tmp:
        images[0].save(tmp, save_all=True, append_images=images[1:],
                       duration=max(1, int(round(1000.0 / fps))), loop=0, optimize=False)


def _write_mp4(frames, path: Path, fps: float) -> None:
    import subprocess

    h, w = frames[0].shape[:2]
    cmd = [shutil.which("ffmpeg") or "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo",
           "-pix_fmt", "rgba", "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-",
           "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p"]
    with atomic_path(path) as tmp:
        proc = subprocess.run(cmd + [str(tmp)], input=b"".join(f.tobytes() for f in frames),
                              capture_output=True, check=False)
        if proc.returncode != 0:
            raise VisualizationError(f"animate: ffmpeg failed to write '{path}': "
                                     f"{proc.stderr.decode(errors='replace').strip()[-300:]}",
                                     path=str(path))


def plot_trajectories(res, path: str | os.PathLike[str] | None = None):
    """Plot the paths of the masses in the plane and the joint coordinates over time.

    Left: ``y`` against ``x`` for every mass (its centre of mass) and link end. Right: the
    coordinates of every joint (``q`` in rad of revolute joints, ``s`` in m of prismatic
    ones) against time.

    Parameters
    ----------
    res : SimResult
        Log of a multibody model.
    path : str or path-like, optional
        Write the figure here (format by suffix).

    Returns
    -------
    matplotlib.figure.Figure
    """
    mech = find_mechanism(res)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.5), layout="constrained")
    ax_xy, ax_t = fig.subplots(1, 2)
    for comp, f, com in mech.masses:
        p = com or f
        ax_xy.plot(res[f"{p}.x"], res[f"{p}.y"], label=comp)
    for g in mech.ground:
        ax_xy.plot(res[f"{g}.x"][0], res[f"{g}.y"][0], "^", color="0.3")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set_xlabel("x [m]")
    ax_xy.set_ylabel("y [m]")
    ax_xy.grid(True, alpha=0.3)
    if mech.masses:
        ax_xy.legend(loc="best", fontsize="small")
    names = set(res.names)
    for j in mech.joints:
        comp = j.rsplit(".", 1)[0]
        for coord in ("q", "s"):
            if f"{comp}.{coord}" in names:
                ax_t.plot(res.t, res[f"{comp}.{coord}"], label=f"{comp}.{coord}")
    for comp, _, _ in mech.links:   # prismatic joints move their frames apart
        if f"{comp}.s" in names:
            ax_t.plot(res.t, res[f"{comp}.s"], label=f"{comp}.s")
    ax_t.set_xlabel("t [s]")
    ax_t.set_ylabel("joint coordinate [rad or m]")
    ax_t.grid(True, alpha=0.3)
    if ax_t.lines:
        ax_t.legend(loc="best", fontsize="small")
    if res.model_name:
        fig.suptitle(res.model_name)
    if path is not None:
        save_figure(fig, path, dpi=100)
    return fig
