"""The instructor's tools: hidden cases, points per test group, the CSV, Gradescope's results.json
(validated against the schema written from Gradescope's documentation) and the autograder zip."""

from __future__ import annotations

import ast
import csv
import io
import json
import subprocess
import sys
import zipfile
from pathlib import Path

import jsonschema
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
COURSE = REPO / "course"
GRADERS = COURSE / "graders"
SCHEMA = json.loads((Path(__file__).resolve().parent / "gradescope_results.schema.json").read_text())


def grade(*arguments: str, cwd: Path = REPO) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(COURSE / "grade.py"), *arguments],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


def lookup_table_submission() -> str:
    """An ex01 "solution" that answers the public cases from a table computed offline (by the head's
    first coordinate), and guesses the two end frames otherwise."""
    sys.path.insert(0, str(GRADERS))
    try:
        import test_ex01_velocity_keypoints as grader
    finally:
        sys.path.remove(str(GRADERS))
    from toolimit.align.keypoints import velocity_keypoints

    table = {}
    for seed in range(8):
        demo = grader.random_demo(seed)
        for fraction in (0.05, 0.1, 0.3):
            key = f"{demo.head[0, 0]:.9f} {fraction}"
            table[key] = [int(frame) for frame in velocity_keypoints(demo, fraction)]
    return (
        "import numpy as np\n\n"
        f"TABLE = {table!r}\n\n\n"
        "def velocity_keypoints(demo, fraction=0.05):\n"
        '    key = f"{demo.head[0, 0]:.9f} {fraction}"\n'
        "    return np.array(TABLE.get(key, [0, demo.n_frames - 1]))\n"
    )


@pytest.fixture(scope="module")
def lookup_class(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("lookup")
    (folder / "table").mkdir()
    (folder / "table" / "ex01_velocity_keypoints.py").write_text(lookup_table_submission())
    (folder / "reference").symlink_to(COURSE / "solutions")
    return folder


def test_a_public_case_lookup_table_passes_public_cases_and_fails_hidden_ones(lookup_class, tmp_path):
    public, hidden = tmp_path / "public.json", tmp_path / "hidden.json"
    for out, extra in ((public, ()), (hidden, ("--hidden-seed", "2026"))):
        result = grade(str(lookup_class), "--exercise", "ex01", "--jobs", "2", "--out", str(out), *extra)
        assert result.returncode == 0, result.stderr
    table_public = json.loads(public.read_text())["table"]["ex01_velocity_keypoints"]
    table_hidden = json.loads(hidden.read_text())["table"]["ex01_velocity_keypoints"]
    matching = "test_ex01_keypoints_match_reference"
    assert table_public["groups"][matching][0] == table_public["groups"][matching][1]
    assert table_hidden["groups"][matching][0] == 0.0, table_hidden["groups"]
    assert table_hidden["score"] <= 0.5 * table_hidden["max_score"]
    assert not any("[" + str(seed) + "-" in test for test in table_hidden["tests"] for seed in range(8))
    reference_hidden = json.loads(hidden.read_text())["reference"]["ex01_velocity_keypoints"]
    assert reference_hidden["score"] == reference_hidden["max_score"] == 10


def test_weights_name_every_test_group_of_their_grader():
    for grader in sorted(GRADERS.glob("test_ex*.py")):
        tree = ast.parse(grader.read_text())
        groups = {
            node.name for node in tree.body if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")
        }
        weights = next(
            ast.literal_eval(node.value)
            for node in tree.body
            if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "WEIGHTS" for t in node.targets)
        )
        assert set(weights) == groups, grader.name


def test_csv_gradescope_results_and_weights(lookup_class, tmp_path):
    weights = tmp_path / "weights.json"
    weights.write_text(json.dumps({"ex01": {"test_ex01_keypoints_match_reference": 16}}))
    gradescope = tmp_path / "gradescope"
    result = grade(
        str(lookup_class),
        "--exercise",
        "ex01",
        "--hidden-seed",
        "7",
        "--weights",
        str(weights),
        "--csv",
        str(tmp_path / "grades.csv"),
        "--gradescope",
        str(gradescope),
        "--out",
        str(tmp_path / "grades.json"),
    )
    assert result.returncode == 0, result.stderr
    rows = list(csv.DictReader(io.StringIO((tmp_path / "grades.csv").read_text())))
    assert [row["student"] for row in rows] == ["reference", "table"]
    sys.path.insert(0, str(COURSE))
    try:
        import grade as grade_module
    finally:
        sys.path.remove(str(COURSE))
    weighted = {**grade_module.grader_weights("ex01_velocity_keypoints"), "test_ex01_keypoints_match_reference": 16}
    full = f"{sum(weighted.values()):g}"
    assert full != "10" and rows[0]["ex01_velocity_keypoints"] == rows[0]["total"] == rows[0]["max_total"] == full
    assert float(rows[1]["total"]) < 10
    for student in ("reference", "table"):
        results = json.loads((gradescope / student / "results.json").read_text())
        jsonschema.validate(results, SCHEMA)
        assert results["score"] == pytest.approx(sum(test["score"] for test in results["tests"]))
    reference = json.loads((gradescope / "reference" / "results.json").read_text())
    assert f"{reference['score']:g}" == full and all(test["status"] == "passed" for test in reference["tests"])
    table = json.loads((gradescope / "table" / "results.json").read_text())
    failed = [test for test in table["tests"] if test["status"] == "failed"]
    assert failed and all("expected keypoints" in test["output"] for test in failed if "match" in test["name"])


def test_schema_refuses_what_gradescope_does_not_document():
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"tests": [{"name": "no score"}]}, SCHEMA)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"score": 1, "tests": [{"score": 1, "status": "partial"}]}, SCHEMA)


def test_bad_weights_are_refused_with_one_line(tmp_path):
    weights = tmp_path / "weights.json"
    weights.write_text(json.dumps({"ex01": {"test_ex01_no_such_group": 3}}))
    result = grade(str(COURSE), "--weights", str(weights))
    assert result.returncode == 2 and "has no test group test_ex01_no_such_group" in result.stderr


def test_autograder_zip_holds_the_graders_a_wheel_and_no_solution(tmp_path):
    out = tmp_path / "autograder.zip"
    result = grade("autograder", str(out), "--exercise", "ex01", "--hidden-seed", "11")
    assert result.returncode == 0, result.stderr
    with zipfile.ZipFile(out) as archive:
        names = set(archive.namelist())
        run = archive.read("run_autograder").decode()
        mode = archive.getinfo("run_autograder").external_attr >> 16
    assert {"setup.sh", "run_autograder", "grade.py", "graders/conftest.py", "graders/student_process.py"} <= names
    assert any(name.startswith("toolimit-") and name.endswith(".whl") for name in names)
    assert not any("solutions" in name for name in names)
    assert "--hidden-seed 11" in run and "--exercise ex01_velocity_keypoints" in run and mode & 0o111
    solutions = {path.read_bytes() for path in (COURSE / "solutions").glob("*.py")}
    with zipfile.ZipFile(out) as archive:
        wheel_name = next(name for name in names if name.endswith(".whl"))
        (tmp_path / wheel_name).write_bytes(archive.read(wheel_name))
        assert not any(archive.read(name) in solutions for name in names)
    with zipfile.ZipFile(tmp_path / wheel_name) as wheel:
        assert all(name.startswith("toolimit") for name in wheel.namelist()), "the wheel holds toolimit only"


def test_hidden_seeds_differ_from_the_public_ones(monkeypatch):
    sys.path.insert(0, str(GRADERS))
    try:
        import grading
    finally:
        sys.path.remove(str(GRADERS))
    monkeypatch.delenv(grading.HIDDEN_SEED_ENV, raising=False)
    assert grading.case_seeds(4, 10) == [10, 11, 12, 13]
    monkeypatch.setenv(grading.HIDDEN_SEED_ENV, "5")
    hidden = grading.case_seeds(8)
    assert len(set(hidden)) == 8 and min(hidden) >= 1000 and hidden == grading.case_seeds(8)
    assert np.intersect1d(hidden, grading.case_seeds(8, 1)).size == 0
