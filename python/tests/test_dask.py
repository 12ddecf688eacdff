"""The Dask recipe of docs/python.md, run on a local dask.distributed cluster of two worker
processes over a folder of clouds: its summary equals the CLI's --summary of the folder."""

import glob
import os

import numpy as np
from dask.distributed import Client, LocalCluster

import afford
from conftest import write_ply


def summary_with_dask(folder: str, client: Client) -> str:
    # The recipe of docs/python.md ("On a cluster").
    files = sorted(glob.glob(os.path.join(folder, "*.ply")))
    futures = client.map(afford.detect_file, files, threads=1)
    results = client.gather(futures)
    return afford.to_summary(results)


def test_dask_over_a_folder_equals_the_cli_summary(sample, cli, tmp_path):
    room = afford.read(sample)
    folder = tmp_path / "scans"
    folder.mkdir()
    # The room, and its two halves along x (each keeps some of the furniture).
    middle = np.median(room[:, 0])
    write_ply(folder / "room.ply", room)
    write_ply(folder / "left.ply", room[room[:, 0] < middle])
    write_ply(folder / "right.ply", room[room[:, 0] >= middle])
    out = tmp_path / "summary.csv"
    p = cli("detect", str(folder), "--summary", str(out))
    assert p.returncode == 0, p.stderr
    expected = out.read_text()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with Client(cluster) as client:
            got = summary_with_dask(str(folder), client)
            assert len(client.scheduler_info()["workers"]) == 2
    assert got == expected
    rows = expected.splitlines()
    assert len(rows) == 4, "a header and three files"
    assert rows[1:] != [rows[1]] * 3, "the halves afford different things"
