"""The renderer benchmark runs on the real world, and both renderers see the same scene."""

from benchmark.perf.render import main


def test_perf_render_runs_and_both_renderers_agree(capsys):
    rates = main(["--frames", "4", "--repeats", "2"])
    out = capsys.readouterr().out
    assert "ratio ours / MuJoCo" in out and "ray-cast capsules per frame" in out
    assert all(rates[k] > 0 for k in ("depth_labels_fps", "depth_labels_sensor_ds325_fps",
                                       "depth_labels_sensor_kinect-v1_fps", "depth_labels_sensor_ideal_fps",
                                       "skin_depth_labels_fps", "skin_depth_labels_sensor_ds325_fps",
                                       "mujoco_depth_fps"))
    assert "ratio skin / primitives" in out
    assert rates["agreement_median_m"] < 1e-5
    assert rates["agreement_within_0.1mm"] > 0.9
