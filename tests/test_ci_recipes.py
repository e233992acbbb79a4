"""The CI recipes in docs/recipes run as written (issue 17 item 5): their commands, not the CI services.

Each recipe's shell lines are taken from the file (GitLab ``script:``, GitHub ``run:``, the Kubernetes
container's ``args``), the installation lines left out (the tools are installed here), CI variables set
as the service would, and run with bash in a folder seeded with ``examples/``. Artifact up/downloads
are no-ops: every stage runs in the same folder. The Kubernetes workers run against a fresh database on
the real PostgreSQL server.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.slow
pytest_plugins = ["batch_stores"]             # the pg_url fixture

ROOT = Path(__file__).resolve().parents[1]
RECIPES = ROOT / "docs" / "recipes"
INSTALL = re.compile(r"\bpip install\b|python3 -m venv")


def seeded(tmp_path: Path) -> Path:
    shutil.copytree(ROOT / "examples" / "coverage", tmp_path / "examples" / "coverage")
    return tmp_path


def shell(line: str, cwd: Path, **variables: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", NO_COLOR="1",
               **variables)
    if "SCENARIO_STORE" not in variables:
        env.pop("SCENARIO_STORE", None)
    return subprocess.run(["bash", "-ec", line], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_the_gitlab_recipe(tmp_path):
    recipe = yaml.safe_load((RECIPES / "gitlab-ci.yml").read_text())
    folder = seeded(tmp_path)
    for line in recipe["vary"]["script"]:
        assert shell(line, folder).returncode == 0
    total = recipe["run"]["parallel"]
    for index in range(1, total + 1):
        for line in recipe["run"]["script"]:
            done = shell(line, folder, CI_NODE_INDEX=str(index), CI_NODE_TOTAL=str(total))
            assert done.returncode in (0, 1), done.stdout + done.stderr       # 1: some variants fail by design
    assert len(list((folder / "results").glob("shard-*/test.xml"))) == total
    for line in recipe["coverage"]["script"]:
        done = shell(line, folder)
        assert done.returncode == 0, line + "\n" + done.stdout + done.stderr
    assert (folder / "coverage.html").stat().st_size > 1000
    _assert_every_shard_merged(done.stdout, len(list((folder / "out").glob("*.sce"))))


def _assert_every_shard_merged(report: str, variants: int) -> None:
    """The recipe's last line is the plain report of the merged shards: complete, every variant counted."""
    head = report.splitlines()[0]
    assert head.endswith("[complete]") and f": {variants} run(s)" in head, report
    assert "INCOMPLETE" not in report


def test_the_github_workflow(tmp_path):
    workflow = yaml.safe_load((RECIPES / "github-workflow.yml").read_text())
    folder = seeded(tmp_path)
    jobs = workflow["jobs"]

    def runs(job: str) -> list[str]:
        return [s["run"] for s in jobs[job]["steps"] if "run" in s and not INSTALL.search(s["run"])]

    for line in runs("vary"):
        assert shell(line, folder).returncode == 0
    for shard in jobs["run"]["strategy"]["matrix"]["shard"]:
        for line in runs("run"):
            done = shell(line.replace("${{ matrix.shard }}", str(shard)), folder)
            assert done.returncode in (0, 1), done.stdout + done.stderr
    variants = len(list((folder / "out").glob("*.sce")))
    shutil.rmtree(folder / "out")                   # the coverage job downloads the results only
    for line in runs("coverage"):
        done = shell(line, folder)
        assert done.returncode == 0, line + "\n" + done.stdout + done.stderr
    assert runs("coverage")[-1].startswith("scenario_coverage report results --fail-under")
    assert f": {variants} run(s)" in done.stdout.splitlines()[0]
    for shard in jobs["run"]["strategy"]["matrix"]["shard"]:      # what the variation declared travels along
        declared = (folder / "results" / f"shard-{shard}" / "declared.json").read_text(encoding="utf-8")
        assert '"key": "cut_in.ego_speed", "values": ["30kph", "50kph", "70kph", "90kph"]' in declared
    _assert_every_shard_merged(done.stdout, variants)


def k8s_documents() -> dict[str, dict]:
    """The manifests of the Kubernetes recipe by kind."""
    return {doc["kind"]: doc for doc in yaml.safe_load_all((RECIPES / "k8s-indexed-job.yaml").read_text())}


def test_the_kubernetes_manifests_validate_against_the_kubernetes_schema():
    import kubernetes_validate

    documents = k8s_documents()
    assert sorted(documents) == ["Job", "PersistentVolumeClaim", "Secret"]
    for document in documents.values():
        kubernetes_validate.validate(document, kubernetes_validate.latest_version(), strict=True)
    job = documents["Job"]["spec"]["template"]["spec"]
    assert job["volumes"][0]["persistentVolumeClaim"]["claimName"] == documents["PersistentVolumeClaim"]["metadata"]["name"]
    secret = job["containers"][0]["env"][0]["valueFrom"]["secretKeyRef"]
    assert secret == {"name": documents["Secret"]["metadata"]["name"], "key": "url"}
    assert "url" in documents["Secret"]["stringData"]
    broken = dict(documents["Job"], spec=dict(documents["Job"]["spec"], paralelism=4))   # the validator can fail
    with pytest.raises(kubernetes_validate.ValidationError):
        kubernetes_validate.validate(broken, kubernetes_validate.latest_version(), strict=True)


def test_the_worker_image_installs_this_repository(tmp_path):
    """The Job's image comes from docs/recipes/Containerfile, which installs the repository itself: it copies
    every package pyproject.toml ships, and the wheel built from them carries the grammar and libraries."""
    import zipfile

    import tomllib

    containerfile = (RECIPES / "Containerfile").read_text()
    copied = set(re.findall(r"^COPY (\w+) /src/\1$", containerfile, re.MULTILINE))
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    shipped = {name.rstrip("*") for name in project["tool"]["setuptools"]["packages"]["find"]["include"]}
    assert copied == shipped
    assert "pip install --no-cache-dir /src" in containerfile and "USER 1000" in containerfile
    assert k8s_documents()["Job"]["spec"]["template"]["spec"]["containers"][0]["image"].endswith(
        "/scenario-coverage:0.1.0")
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w",
                            str(tmp_path), str(ROOT)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    (wheel,) = tmp_path.glob("scenario_coverage-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "coverage_engine/parse/grammar.lark" in names and "coverage_engine/osc/types.osc" in names
    assert {f"executor/simulations/{lib}/lib_osc/{lib}.osc" for lib in ("ros", "nav2", "gazebo", "pybullet")} <= names


def test_the_kubernetes_workers_share_one_postgresql_store(tmp_path, pg_url):
    spec = k8s_documents()["Job"]["spec"]
    container = spec["template"]["spec"]["containers"][0]
    command = container["args"][0]
    assert not INSTALL.search(command) and command.startswith("scenario_batch_execution worker")
    folder = seeded(tmp_path)
    assert shell("scenario_variation examples/coverage/cut_in.osc --strategy pairwise --seed 1 -o out",
                 folder).returncode == 0
    enqueue = shell(f'scenario_batch_execution -i out -o {folder / "results"} --enqueue-only --store "{pg_url}"',
                    folder)
    assert enqueue.returncode == 0, enqueue.stderr
    workers = [subprocess.Popen(["bash", "-ec", command.replace("/results", str(folder / "results"))], cwd=folder,
                                env=dict(os.environ, SCENARIO_STORE=pg_url, NO_COLOR="1",
                                         PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"),
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
               for _ in range(min(2, spec["parallelism"]))]
    for worker in workers:
        worker.communicate(timeout=300)
    report = shell(f'scenario_batch_execution report --store "{pg_url}" --json -o report.xml', folder)
    assert report.returncode in (0, 1), report.stderr
    assert '"passed": 20' in report.stdout and '"failed": 4' in report.stdout
