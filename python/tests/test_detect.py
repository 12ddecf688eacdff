"""The Python package against the command line of the same wheel: same documents, same
numbers, whatever the array's type, order, threads or frame."""

import csv
import io
import json
import pickle
import threading

import numpy as np
import pytest

import afford
from conftest import ROOT, write_ply

NAME = "data/sample/room.ply"


@pytest.fixture(scope="module")
def points(sample):
    return afford.read(sample)


@pytest.fixture(scope="module")
def result(points):
    return afford.detect(points, name=NAME)


def test_the_sample_as_an_array_gives_the_cli_json(result, sample_cli_json):
    assert result.to_dict() == sample_cli_json
    cli = sample_cli_json["files"][0]["detections"]
    assert len(result.detections) == len(cli) >= 5, "the sample holds several seats"
    for d, c in zip(result.detections, cli):
        # Full precision here, rounded to 4 decimals in the JSON.
        assert np.all(np.abs(d.position - c["position"]) <= 0.5e-4 + 1e-12)
        assert abs(d.score - c["score"]) <= 0.5e-4 + 1e-12
        assert abs(d.stability - c["stability"]) <= 0.5e-4 + 1e-12
        assert d.affordances == c["affordances"]
        assert (d.hierarchy, d.agent, d.height) == (c["hierarchy"], c["agent"], c["height"])
        assert len(d.segment) == d.segment_points == c["segment_points"]


def test_detect_file_gives_the_cli_bytes(monkeypatch, cli, tmp_path):
    monkeypatch.chdir(ROOT)
    r = afford.detect_file(NAME)
    out = tmp_path / "a.json"
    csv_out = tmp_path / "a.csv"
    summary = tmp_path / "s.csv"
    p = cli("detect", NAME, "--json", str(out), "--csv", str(csv_out), "--summary", str(summary))
    assert p.returncode == 0, p.stderr
    assert r.to_json() == out.read_text()
    assert afford.to_csv([r]) == csv_out.read_text()
    assert afford.to_summary([r]) == summary.read_text()
    assert r.to_csv_rows() == list(csv.DictReader(io.StringIO(csv_out.read_text())))
    assert len(r.labels) == len(afford.read(NAME)) == r.points


def test_labels_follow_the_input_rows(result, points):
    labels = result.labels
    assert labels.dtype == np.int32 and labels.shape == (len(points),)
    assert labels.min() == -1, "the floor and the walls belong to no seat"
    assert set(np.unique(labels)) - {-1} <= set(range(len(result.detections)))
    for d in result.detections:
        # A point is labelled with the first detection whose segment holds it.
        assert np.all(labels[d.segment] <= d.index)
        assert np.all(labels[d.segment] >= 0)
        assert set(np.flatnonzero(labels == d.index)) <= set(d.segment.tolist())
    assert np.array_equal(result.transform, np.eye(4))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("order", ["C", "F"])
def test_float32_float64_c_and_fortran_agree(points, result, dtype, order):
    # The sample is float32 on disk, so float32 holds its points exactly.
    a = np.array(points, dtype=dtype, order=order)
    assert a.flags.f_contiguous == (order == "F")
    assert afford.detect(a, name=NAME) == result


def test_other_real_dtypes_and_array_likes_convert(points, result):
    big_endian = np.array(points, dtype=">f8")
    assert afford.detect(big_endian, name=NAME) == result
    small = points[:2000]
    assert afford.detect(small.tolist()) == afford.detect(small)


def test_threads_1_and_2_give_the_same(points):
    one = afford.detect(points, threads=1)
    two = afford.detect(points, threads=2)
    assert one == two
    assert one.to_json() == two.to_json()


def test_a_result_pickles(result):
    back = pickle.loads(pickle.dumps(result))
    assert back == result
    assert back.to_json() == result.to_json()
    assert back.detections[0].position.tolist() == result.detections[0].position.tolist()


def camera_copy(world: np.ndarray) -> np.ndarray:
    """The sample seen from a camera 1.6 m up, 3 m in front of the room, pitched 25 deg
    down (x right, y down, z forward), in millimetres: crates/afford-cli/tests/cli.rs's copy."""
    direction = np.array([-0.9, 0.2, -0.42])
    z = direction / np.linalg.norm(direction)
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    look = np.column_stack([x, y, z])  # nalgebra's face_towards(direction, +z)
    flip = np.diag([-1.0, -1.0, 1.0])  # 180 deg about z: the camera's y is down
    rot = look @ flip
    t = np.array([3.0, 0.3, 1.6])
    return (world - t) @ rot * 1000.0


def test_a_camera_frame_in_millimetres_with_nan_rows(points, result, cli, tmp_path):
    cam = camera_copy(points).astype(np.float32)
    nan_rows = [0, 17, 5000, len(cam) - 1]
    cam = np.insert(cam, nan_rows, np.nan, axis=0)
    cam[100, 1] = np.inf
    path = tmp_path / "camera.ply"
    write_ply(path, cam)
    frame = dict(camera=True, units="mm", floor="auto")
    r = afford.detect(cam, name=str(path), **frame)
    # The same as the CLI on the same numbers in a file...
    out = tmp_path / "camera.json"
    p = cli("detect", str(path), "--camera", "--units", "mm", "--floor", "auto", "--json", str(out))
    assert p.returncode == 0, p.stderr
    assert r.to_json() == out.read_text()
    assert r.dropped_non_finite == 5
    assert r.frame is not None and r.frame.startswith("frame: mm to metres")
    # ...and the same seats as the sample in its own frame: each detection of the
    # sample, taken into the camera copy and through the transform found, lands near
    # its own detection of the camera run with the same affordances. Hypotheses lie on
    # the height-map grid of each frame, so a place moves by a few 5 cm cells (most along
    # the sofa, where any place is as good); the other seats are over a metre away.
    assert r.affordances == result.affordances
    assert len(r.detections) == len(result.detections)
    matched = set()
    for b in result.detections:
        seen = camera_copy(b.position[None, :])[0]
        expected = r.transform[:3, :3] @ seen + r.transform[:3, 3]
        same = [a for a in r.detections if a.affordances == b.affordances]
        near = min(same, key=lambda a: np.linalg.norm(a.position - expected))
        assert np.linalg.norm(near.position - expected) < 0.35
        matched.add(near.index)
    assert matched == set(range(len(r.detections)))
    # Outputs keep the input rows; the dropped ones have no label.
    assert r.labels.shape == (len(cam),)
    dropped = np.flatnonzero(~np.isfinite(cam).all(axis=1))
    assert np.all(r.labels[dropped] == -1)
    # The transform maps the camera points onto the levelled world frame.
    finite = np.isfinite(cam).all(axis=1)
    world = cam[finite].astype(np.float64) @ r.transform[:3, :3].T + r.transform[:3, 3]
    floor = world[:, 2][np.abs(world[:, 2]) < 0.05]
    assert len(floor) > len(world) // 4 and abs(np.median(floor)) < 0.01


def test_a_floor_away_from_zero_is_a_warning(points, result):
    assert result.warnings == []
    low = points - np.array([0.0, 0.0, 1.3])
    r = afford.detect(low, name="low", affordances="sitting")
    assert len(r.warnings) == 1 and "--floor auto" in r.warnings[0], r.warnings
    r = afford.detect(low, name="low", affordances="sitting", floor="auto")
    assert r.warnings == [] and len(r.detections) > 0


def test_an_array_of_the_wrong_shape_is_a_value_error(points):
    with pytest.raises(ValueError, match=r"shape \(N, 3\), got shape \(89833, 2\)"):
        afford.detect(points[:, :2])
    with pytest.raises(ValueError, match="float32 or float64"):
        afford.detect(np.array([["a", "b", "c"]]))


def test_a_missing_model_file_is_an_os_error(points, tmp_path):
    missing = tmp_path / "nosuch.toml"
    with pytest.raises(OSError, match="nosuch.toml: no such file"):
        afford.detect(points, affordances=[str(missing)])
    with pytest.raises(FileNotFoundError, match="nosuch.ply: cannot read"):
        afford.detect_file(tmp_path / "nosuch.ply")


def test_bad_arguments_are_value_errors_in_the_cli_words(points):
    with pytest.raises(ValueError, match="units: unknown units 'inch'"):
        afford.detect(points, units="inch")
    with pytest.raises(ValueError, match="17.5 m is outside 0.3-3.0 m"):
        afford.detect(points, heights=17.5)
    with pytest.raises(ValueError, match="heights: expected numbers"):
        afford.detect(points, heights="tall")
    with pytest.raises(ValueError, match="threads"):
        afford.detect(points, threads=0)
    with pytest.raises(ValueError, match="transform"):
        afford.detect(points, transform=np.zeros((3, 3)))


def test_a_transform_array_is_applied_as_on_the_cli(points, result):
    shift = np.eye(4)
    shift[:3, 3] = [-1.0, 2.0, 0.0]
    r = afford.detect(points + [1.0, -2.0, 0.0], transform=shift)
    assert np.allclose(r.transform, shift)
    assert r.affordances == result.affordances
    for a, b in zip(r.detections, result.detections):
        assert np.allclose(a.position, b.position, atol=1e-6)


def test_the_gil_is_released_while_detecting(points):
    done = threading.Event()
    worker = threading.Thread(target=lambda: (afford.detect(points, threads=1), done.set()))
    ticks = 0
    worker.start()
    while not done.wait(0.001):
        ticks += 1
    worker.join()
    # Holding the GIL for the whole detection would let this loop run once or twice.
    assert ticks >= 20


def test_the_wheel_installs_the_command_line(cli):
    p = cli("--version")
    assert p.returncode == 0 and p.stdout.startswith("afford ")
    p = cli("detect", "nosuch.ply")
    assert p.returncode == 2 and "nosuch.ply: cannot read" in p.stderr
