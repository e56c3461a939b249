"""Animation and trajectory plots of mechanisms (mechatron.viz)."""

import numpy as np
import pytest
from PIL import Image

import mechatron as mt
from mechatron.errors import DataError
from mechatron.library.multibody import mechanisms as mech
from mechatron.results import SimResult
from mechatron.viz import VisualizationError, animate, find_mechanism, plot_trajectories


@pytest.fixture(scope="module")
def pendulum():
    return mt.simulate(mech.double_pendulum(), 2.0, rtol=1e-8, atol=1e-10)


def test_find_mechanism_reads_the_parts_from_the_log(pendulum):
    m = find_mechanism(pendulum)
    assert sorted(c for c, _, _ in m.links) == ["rod1", "rod2"]
    assert sorted(m.joints) == ["j1.frame_a", "j2.frame_a"]
    assert sorted(c for c, _, _ in m.masses) == ["m1", "m2"]
    assert m.ground == ["world.frame"]


def test_animate_writes_a_gif_with_one_frame_per_time_step(pendulum, tmp_path):
    path = pendulum.animate(tmp_path / "dp.gif", fps=10, dpi=50)
    assert path == tmp_path / "dp.gif"
    with Image.open(path) as im:
        assert im.n_frames == 21                  # 2 s at 10 fps, both ends included
        assert im.size == (250, 250)              # 5 in at 50 dpi
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(im.n_frames - 1)
        last = np.asarray(im.convert("RGB")).copy()
    assert np.any(first != last), "the mechanism moves between the first and last frame"
    with Image.open(animate(pendulum, tmp_path / "slow.gif", fps=10, speed=0.5,
                            max_frames=15, dpi=30)) as im:
        assert im.n_frames == 15                  # capped by max_frames


def test_animate_rejects_bad_requests(pendulum, tmp_path, monkeypatch):
    with pytest.raises(VisualizationError, match=r"\.gif or \.mp4"):
        pendulum.animate(tmp_path / "dp.avi")
    with pytest.raises(DataError, match="must be > 0"):
        pendulum.animate(tmp_path / "dp.gif", fps=0)
    monkeypatch.setattr("shutil.which", lambda name: None)
    with pytest.raises(VisualizationError, match="ffmpeg"):
        pendulum.animate(tmp_path / "dp.mp4")
    plain = SimResult([0.0, 1.0], [[0.0, 1.0]], ["j.w"], ["rad/s"], model_name="rot")
    with pytest.raises(VisualizationError, match="no multibody frame"):
        plain.animate(tmp_path / "x.gif")


def test_animate_writes_mp4_when_ffmpeg_is_there(pendulum, tmp_path):
    import shutil
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not on the PATH")
    path = pendulum.animate(tmp_path / "dp.mp4", fps=10, dpi=40)
    assert path.stat().st_size > 0


def test_trajectory_plot_draws_the_logged_paths(pendulum, tmp_path):
    fig = plot_trajectories(pendulum, tmp_path / "traj.png")
    assert (tmp_path / "traj.png").stat().st_size > 0
    ax_xy, ax_t = fig.axes
    lines = {ln.get_label(): ln for ln in ax_xy.lines}
    np.testing.assert_array_equal(lines["m2"].get_xdata(), pendulum["m2.frame.x"])
    np.testing.assert_array_equal(lines["m2"].get_ydata(), pendulum["m2.frame.y"])
    labels = sorted(ln.get_label() for ln in ax_t.lines)
    assert labels == ["j1.q", "j2.q"]
