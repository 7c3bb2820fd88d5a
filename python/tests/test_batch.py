"""chisel.batch: one Dask task per volume on a LocalCluster of 2 worker
processes over 8 volumes (the shared CT, MR, label and 2-D images plus
four generated phantoms in four formats) and one broken file — scans of
all, polyhedra of the generated ones: results equal the serial loop's and
the command line's, in input order; GPU tasks go where the GPU is."""

import pytest

import chisel
from conftest import phantoms, without_timings

OPTIONS = dict(level=5, min_voxels=20)


@pytest.fixture(scope="module")
def paths(tmp_path_factory):
    from conftest import DATA, need

    shared = [
        need(DATA / n)
        for n in (
            "headsq/quarter.nhdr",
            "froggy/frogtissue.mhd",
            "HeadMRVolume.mhd",
            "foot/foot.mha",
        )
    ]
    folder = tmp_path_factory.mktemp("phantoms")
    broken = folder / "broken.mha"
    broken.write_text("ObjectType = Image\nNDims = 3\nDimSize = 4 4\n")
    made = phantoms(folder)
    return shared[:2] + [broken] + shared[2:] + made


def test_serial_batch_reports_every_file_in_order(paths, cli):
    reports = chisel.batch.scan(paths, **OPTIONS)
    assert [r["volume"] for r in reports] == [str(p) for p in paths]
    failed = [r for r in reports if "error" in r]
    assert len(failed) == 1 and failed[0]["volume"].endswith("broken.mha")
    assert failed[0]["error"]["type"] == "FormatError"
    assert "line 4: expected an `ElementDataFile" in failed[0]["error"]["message"]
    # Each report is what `chisel scan PATH --json` prints for that file.
    for path, report in zip(paths[:2], reports[:2]):
        theirs = cli("scan", path, "--level", "5", "--min-voxels", "20", "--backend", "cpu")
        assert without_timings(report) == without_timings(theirs)
    table = chisel.batch.table(reports)
    rows = table.to_dict("records") if hasattr(table, "to_dict") else table
    assert sum(isinstance(r["error"], str) for r in rows) == 1
    assert len(rows) == 1 + sum(len(r["rows"]) for r in reports if "rows" in r)


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster, distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        yield client


def test_local_cluster_equals_the_serial_loop(paths, client):
    serial = chisel.batch.scan(paths, **OPTIONS)
    parallel = chisel.batch.scan(paths, client=client, **OPTIONS)
    assert [without_timings(r) for r in parallel] == [without_timings(r) for r in serial]
    assert sum("rows" in r for r in parallel) == len(paths) - 1


def test_polyhedra_on_the_cluster_equal_the_serial_loop_and_the_cli(paths, client, cli):
    generated = [p for p in paths if "phantoms" in str(p)]  # four phantoms and the broken file
    serial = chisel.batch.polyhedrize(generated, level=5)
    parallel = chisel.batch.polyhedrize(generated, client=client, level=5)
    assert parallel == serial
    assert [("error" in r) for r in serial] == [p.name == "broken.mha" for p in generated]
    good = next(p for p, r in zip(generated, serial) if "error" not in r)
    theirs = cli("polyhedrize", good, "--level", "5", "--backend", "cpu")
    mine = next(r for p, r in zip(generated, serial) if p == good)
    for key in ("object", "topology", "options", "polyhedron", "zkh", "mesh"):
        assert mine[key] == theirs[key], key


def test_gpu_tasks_run_only_where_the_gpu_resource_is(paths, client):
    distributed = pytest.importorskip("distributed")
    small = [p for p in paths if "phantoms" in str(p) and p.name != "broken.mha"]
    # Workers without a GPU resource: GPU tasks ask for none and run anywhere.
    assert chisel.batch._gpu_resources(client, {"backend": "gpu"}) is None
    # Two workers, one with the resource `GPU`: GPU tasks go there only.
    spec = {
        "plain": {"cls": distributed.Nanny, "options": {"nthreads": 1}},
        "gpu": {"cls": distributed.Nanny, "options": {"nthreads": 1, "resources": {"GPU": 1}}},
    }
    scheduler = {"cls": distributed.Scheduler, "options": {"dashboard_address": ":0"}}
    with distributed.SpecCluster(workers=spec, scheduler=scheduler) as cluster, distributed.Client(
        cluster
    ) as gpu_client:
        gpu_client.wait_for_workers(2)
        assert chisel.batch._gpu_resources(gpu_client, {"backend": "gpu"}) == {"GPU": 1}
        assert chisel.batch._gpu_resources(gpu_client, {"backend": "cpu"}) is None
        on_gpu = chisel.batch.scan(small * 2, client=gpu_client, backend="gpu", **OPTIONS)
        ran = gpu_client.run(
            lambda dask_worker: sum(
                1 for entry in dask_worker.state.log if str(entry[0]).startswith("chisel-scan")
            )
        )
        resources = {
            addr: w["resources"]
            for addr, w in gpu_client.scheduler_info()["workers"].items()
        }
    by_resource = {("GPU" in resources[addr]): n for addr, n in ran.items()}
    assert by_resource[False] == 0 and by_resource[True] > 0, (ran, resources)
    on_cpu = chisel.batch.scan(small * 2, **OPTIONS)
    assert [r["backend"] for r in on_gpu] == ["gpu"] * len(on_gpu)
    assert [r["rows"] for r in on_gpu] == [r["rows"] for r in on_cpu]
