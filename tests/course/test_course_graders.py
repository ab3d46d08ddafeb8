"""The course graders grade: they pass the reference solutions, fail the stubs and catch wrong ones.

All submissions are graded in ONE run of ``course/grade.py`` (the instructors' tool, so it is
tested too) over a folder of links: the reference solutions, the untouched exercise stubs, a file
that does not import, and every plausible wrong solution ``wrong_solutions/<variant>/exNN_name.py``.
Exercises and wrong solutions are discovered: each wrong solution lists in ``CAUGHT_BY`` the
grader tests (name prefixes) that must fail on it.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
COURSE = REPO / "course"
WRONG = Path(__file__).resolve().parent / "wrong_solutions"
EXERCISES = sorted(path.stem for path in (COURSE / "exercises").glob("ex*.py"))
VARIANTS = sorted(path.name for path in WRONG.iterdir() if path.is_dir() and path.name.startswith("ex"))


def wrong_solution_file(variant: str) -> Path:
    """The one exNN_name.py file of a wrong solution folder."""
    files = sorted((WRONG / variant).glob("ex*.py"))
    assert len(files) == 1, f"{variant}: expected one exNN_name.py file, found {[f.name for f in files]}"
    return files[0]


def caught_by(variant: str) -> list[str]:
    """The CAUGHT_BY list of a wrong solution: grader test name prefixes that must fail on it."""
    path = wrong_solution_file(variant)
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "CAUGHT_BY" for t in node.targets):
            return list(ast.literal_eval(node.value))
    raise AssertionError(
        f"{path}: add CAUGHT_BY = [...], the grader tests (name prefixes) that must fail on it (course/README.md)"
    )


def grade(submissions: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(COURSE / "grade.py"), str(submissions), *extra],
        cwd=REPO, capture_output=True, text=True, timeout=600, check=False,
    )


@pytest.fixture(scope="module")
def grades(tmp_path_factory) -> dict:
    """Every submission's grades: {submission: {exercise: {"passed", "total", "tests", "messages"}}}.

    The reference solutions, the stubs and the file that does not import are graded on every
    exercise; each wrong solution on its own exercise only (``--exercise``), as an instructor grades
    one week's exercise."""
    folder = tmp_path_factory.mktemp("submissions")
    every = folder / "every_exercise"
    every.mkdir()
    (every / "reference").symlink_to(COURSE / "solutions")
    (every / "stubs").symlink_to(COURSE / "exercises")
    broken = every / "does_not_import"
    broken.mkdir()
    (broken / "ex01_velocity_keypoints.py").write_text("def velocity_keypoints(demo, fraction=0.05)\n    return []\n")
    runs = [(every, ())]
    for exercise in EXERCISES:
        wrong = folder / exercise
        wrong.mkdir()
        for variant in VARIANTS:
            if wrong_solution_file(variant).stem == exercise:
                (wrong / variant).symlink_to(WRONG / variant)
        runs.append((wrong, ("--exercise", exercise)))
    graded: dict = {}
    for submissions, selection in runs:
        out = submissions / "grades.json"
        result = grade(submissions, *selection, "--jobs", "2", "--out", str(out))
        assert result.returncode == 0, result.stderr
        graded |= json.loads(out.read_text())
    return graded


@pytest.mark.parametrize("exercise", EXERCISES)
def test_exercise_has_solution_grader_and_two_wrong_solutions(exercise):
    assert (COURSE / "solutions" / f"{exercise}.py").is_file(), f"no reference solution for {exercise}"
    assert (COURSE / "graders" / f"test_{exercise}.py").is_file(), f"no grader for {exercise}"
    wrong = [variant for variant in VARIANTS if wrong_solution_file(variant).stem == exercise]
    assert len(wrong) >= 2, f"{exercise}: at least two wrong solutions needed, found {wrong}"


@pytest.mark.parametrize("exercise", EXERCISES)
def test_reference_solution_passes_every_grader(grades, exercise):
    result = grades["reference"][exercise]
    assert result["total"] >= 5, f"too few grader tests for {exercise}: {result['total']}"
    assert result["passed"] == result["total"], result["messages"]


@pytest.mark.parametrize("exercise", EXERCISES)
def test_stub_fails_every_grader_with_a_readable_message(grades, exercise):
    result = grades["stubs"][exercise]
    assert result["passed"] == 0 and set(result["tests"].values()) == {"failed"}, result["tests"]
    assert all("is not written yet" in message for message in result["messages"].values()), result["messages"]


@pytest.mark.parametrize("variant", VARIANTS)
def test_wrong_solution_is_caught_by_the_expected_graders(grades, variant):
    exercise, expected = wrong_solution_file(variant).stem, caught_by(variant)
    assert expected, f"{variant}: CAUGHT_BY is empty"
    result = grades[variant][exercise]
    failed = [test for test, outcome in result["tests"].items() if outcome == "failed"]
    for prefix in expected:
        assert any(test.startswith(prefix) for test in failed), f"{variant}: {prefix} did not fail; failed: {failed}"
    assert not any(outcome == "error" for outcome in result["tests"].values()), result["messages"]
    assert set(grades[variant]) == {exercise}, "--exercise graded other exercises too"


def test_missing_or_broken_files_fail_with_a_readable_message(grades):
    broken = grades["does_not_import"]
    assert broken["ex01_velocity_keypoints"]["passed"] == 0
    assert all("cannot be imported: SyntaxError" in m for m in broken["ex01_velocity_keypoints"]["messages"].values())
    for exercise in EXERCISES[1:]:
        missing = broken[exercise]
        assert missing["passed"] == 0
        assert all(f"no file {exercise}.py" in m for m in missing["messages"].values()), missing["messages"]


def test_grade_rejects_an_unknown_exercise(tmp_path):
    result = grade(tmp_path, "--exercise", "ex99_unknown")
    assert result.returncode == 2 and "invalid choice: 'ex99_unknown'" in result.stderr


def test_grade_rejects_a_missing_folder(tmp_path):
    result = grade(tmp_path / "absent")
    assert result.returncode == 2 and "is not a folder" in result.stderr


def test_project_test_run_does_not_collect_the_course():
    assert 'testpaths = ["tests"]' in (REPO / "pyproject.toml").read_text()
