"""The course graders grade: they pass the reference solutions, fail the stubs and catch wrong ones.

All submissions are graded by ``course/grade.py`` (the instructors' tool, so it is tested too) over
folders of links: the reference solutions, the untouched exercise stubs, a file that does not
import, every plausible wrong solution ``wrong_solutions/<variant>/exNN_name.py``, every cheating
one ``cheating_solutions/<variant>/exNN_name.py`` (it calls an existing implementation: 0 points)
and two endless loops. Exercises, wrong and cheating solutions are discovered: each wrong solution
lists in ``CAUGHT_BY`` the grader tests (name prefixes) that must fail on it.
"""

from __future__ import annotations

import ast
import concurrent.futures
import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
COURSE = REPO / "course"
WRONG = Path(__file__).resolve().parent / "wrong_solutions"
CHEATING = Path(__file__).resolve().parent / "cheating_solutions"
EXERCISES = sorted(path.stem for path in (COURSE / "exercises").glob("ex*.py"))
VARIANTS = sorted(path.name for path in WRONG.iterdir() if path.is_dir() and path.name.startswith("ex"))
CHEATS = sorted(path.name for path in CHEATING.iterdir() if path.is_dir() and path.name.startswith("ex"))
#: Submissions that attack the grader rather than call a library: read its frames, patch its checks,
#: start a raw thread, run the library's source again. Each must score at most a quarter.
ATTACKING = Path(__file__).resolve().parent / "attacking_solutions"
ATTACKS = sorted(path.name for path in ATTACKING.iterdir() if path.is_dir() and path.name.startswith("ex"))
HONEST = Path(__file__).resolve().parent / "honest_solutions"
HONEST_VARIANTS = sorted(path.name for path in HONEST.iterdir() if path.is_dir() and path.name.startswith("ex"))
#: A loop the per-call timer inside the student's process cannot interrupt (it swallows every
#: exception): the grader kills that process 10 s after the call's limit.
STUBBORN_LOOP = """import time


def velocity_keypoints(demo, fraction=0.05):
    while True:
        try:
            time.sleep(0.05)
        except BaseException:
            pass
"""
#: A module whose import never ends and swallows every exception: only the per-exercise timeout of
#: grade.py stops it (it kills the grader's process group, the student's process with it).
LOOP_AT_IMPORT = """import time

while True:
    try:
        time.sleep(0.05)
    except BaseException:
        pass
"""
#: An ordinary endless loop: the per-call time limit stops it, the exercise's other tests fail at once.
PLAIN_LOOP = """def velocity_keypoints(demo, fraction=0.05):
    while True:
        pass
"""


def wrong_solution_file(variant: str, folder: Path = WRONG) -> Path:
    """The one exNN_name.py file of a wrong (or cheating) solution folder."""
    files = sorted((folder / variant).glob("ex*.py"))
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
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
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
        for variant in CHEATS:
            if wrong_solution_file(variant, CHEATING).stem == exercise:
                (wrong / variant).symlink_to(CHEATING / variant)
        for variant in HONEST_VARIANTS:
            if wrong_solution_file(variant, HONEST).stem == exercise:
                (wrong / variant).symlink_to(HONEST / variant)
        for variant in ATTACKS:
            if wrong_solution_file(variant, ATTACKING).stem == exercise:
                (wrong / variant).symlink_to(ATTACKING / variant)
        runs.append((wrong, ("--exercise", exercise)))
    loops = folder / "loops"
    for name, source in (
        ("loops_stubbornly", STUBBORN_LOOP),
        ("loops_plainly", PLAIN_LOOP),
        ("loops_at_import", LOOP_AT_IMPORT),
    ):
        (loops / name).mkdir(parents=True)
        (loops / name / "ex01_velocity_keypoints.py").write_text(source)
    (loops / "loops_stubbornly" / "ex02_element_sampling.py").symlink_to(
        COURSE / "solutions" / "ex02_element_sampling.py"
    )
    # first: its 30 s of a sleeping loop overlap the other runs
    runs.insert(0, (loops, ("--exercise", "ex01", "--exercise", "ex02", "--timeout", "30", "--call-timeout", "5")))

    def run(submissions: Path, selection: tuple[str, ...]) -> dict:
        out = submissions / "grades.json"
        result = grade(submissions, *selection, "--jobs", "2", "--out", str(out))
        assert result.returncode == 0, result.stderr
        return json.loads(out.read_text())

    graded: dict = {}
    # two grade.py runs at a time: each run's last exercises would leave a core idle
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        for result in pool.map(lambda args: run(*args), runs):
            graded |= result
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


@pytest.mark.parametrize("variant", CHEATS)
def test_cheating_solution_scores_zero_with_a_message(grades, variant):
    exercise = wrong_solution_file(variant, CHEATING).stem
    result = grades[variant][exercise]
    assert result["status"] == "forbidden" and result["passed"] == 0, (result["status"], result["tests"])
    forbidden = [message for message in result["messages"].values() if message.startswith("0 points for this exercise")]
    assert forbidden and "existing implementation" in forbidden[0], result["messages"]


@pytest.mark.parametrize("variant", ATTACKS)
def test_attack_on_the_grader_scores_at_most_a_quarter(grades, variant):
    exercise = wrong_solution_file(variant, ATTACKING).stem
    result = grades[variant][exercise]
    assert result["total"] > 0 and result["passed"] <= result["total"] / 4, (result["status"], result["tests"])
    assert result["score"] <= 0.25 * result["max_score"], result


@pytest.mark.parametrize("variant", HONEST_VARIANTS)
def test_honest_solution_using_other_toolimit_names_is_not_refused(grades, variant):
    exercise = wrong_solution_file(variant, HONEST).stem
    result = grades[variant][exercise]
    assert result["status"] == "graded" and result["passed"] == result["total"], result["messages"]


def test_untouched_stub_is_one_line_not_attempted(grades):
    assert {grade["status"] for grade in grades["stubs"].values()} == {"not attempted"}
    sys.path.insert(0, str(COURSE))
    try:
        import grade as grade_module
    finally:
        sys.path.remove(str(COURSE))
    report = grade_module.check_report(grades["stubs"]).splitlines()
    assert len(report) == len(EXERCISES) and all(line.endswith("not attempted") for line in report), report


def test_an_endless_loop_costs_only_its_exercise(grades):
    stubborn = grades["loops_stubbornly"]
    hidden = stubborn["ex01_velocity_keypoints"]  # the student's process is killed 10 s after the call's limit
    assert hidden["status"] == "graded" and hidden["passed"] == 0 and hidden["score"] == 0, hidden
    assert hidden["seconds"] < 30 and "did not return within 5 s" in next(iter(hidden["messages"].values()))
    plain = grades["loops_plainly"]["ex01_velocity_keypoints"]
    assert plain["status"] == "graded" and plain["passed"] == 0, plain
    assert plain["seconds"] < 30 and "did not return within 5 s" in next(iter(plain["messages"].values()))
    at_import = grades["loops_at_import"]["ex01_velocity_keypoints"]
    assert at_import["status"] == "timed out" and at_import["score"] == 0, at_import
    assert "stopped after 30 s" in at_import["messages"]["run"]
    other = stubborn["ex02_element_sampling"]
    assert other["status"] == "graded" and other["passed"] == other["total"] > 0, other["messages"]


def test_messages_are_plain_sentences(grades):
    """No pytest assertion rewriting, no numpy reprs, in any message of any graded submission."""
    for student, outcomes in grades.items():
        for exercise, result in outcomes.items():
            for test, message in result["messages"].items():
                for noise in ("assert ", "AssertionError", "array(", "dtype=", "tensor(", "+  where", "Traceback"):
                    assert noise not in message, f"{student} {exercise} {test}: {noise!r} in\n{message}"


def test_gae_message_names_the_first_wrong_step_of_the_backward_recursion(grades):
    messages = grades["ex05_off_by_one_done"]["ex05_ppo_objective"]["messages"]
    gae = [message for test, message in messages.items() if test.startswith("test_ex05_gae_matches")]
    assert gae and all("going backwards from t = T-1 = 11, the first wrong advantage is at t = " in m for m in gae)


def test_bundle_holds_no_solution_and_checks_itself(tmp_path):
    out = tmp_path / "bundle"
    result = subprocess.run(
        [sys.executable, str(COURSE / "grade.py"), "bundle", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    files = {path.relative_to(out).as_posix() for path in out.rglob("*") if path.is_file()}
    assert {"README.md", "grade.py", "graders/conftest.py", "graders/grading.py", "requirements.txt"} <= files
    (wheel,) = out.glob("toolimit-*.whl")
    assert f"./{wheel.name}[course]" in (out / "requirements.txt").read_text()
    assert {f"exercises/{exercise}.py" for exercise in EXERCISES} <= files
    assert {f"graders/test_{exercise}.py" for exercise in EXERCISES} <= files
    solutions = {path.read_bytes() for path in (COURSE / "solutions").glob("*.py")}
    assert not any("solution" in name for name in files), files
    assert not any((out / name).read_bytes() in solutions for name in files)
    notebooks = sorted(out.glob("notebooks/*.ipynb"))
    assert [path.name[:2] for path in notebooks] == ["01", "02", "03", "04", "05", "06"]
    assert (out / "notebook_checks.py").is_file() and (out / "data" / "demos" / "spade_00.npz").is_file()
    for path in notebooks:
        handed_out = json.loads(path.read_text())
        code = ["".join(cell["source"]) for cell in handed_out["cells"] if cell["cell_type"] == "code"]
        assert not any("SOLUTION" in source for source in code), path.name
        assert any('raise NotImplementedError("exercise: write this part")' in source for source in code)
        assert all(not cell.get("outputs") for cell in handed_out["cells"] if cell["cell_type"] == "code")
        source = json.loads((REPO / "notebooks" / path.name).read_text())
        for cell in source["cells"]:
            text = "".join(cell["source"])
            if "### BEGIN SOLUTION" in text:
                answer = text.split("### BEGIN SOLUTION")[1].split("### END SOLUTION")[0]
                lines = [line.strip() for line in answer.splitlines() if len(line.strip()) > 25]
                assert lines and not any(line in "".join(code) for line in lines), path.name
    again = subprocess.run(
        [sys.executable, str(COURSE / "grade.py"), "bundle", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert again.returncode == 2 and "not an empty folder" in again.stderr
    check = subprocess.run(
        [sys.executable, str(out / "grade.py"), "check", "--exercise", "ex05"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert check.returncode == 0, check.stderr
    assert check.stdout.split() == ["ex05_ppo_objective", "not", "attempted"], check.stdout
    bare = tmp_path / "exam"
    result = subprocess.run(
        [sys.executable, str(COURSE / "grade.py"), "bundle", str(bare), "--without-graders", "--wheel", str(wheel)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert sorted(path.name for path in bare.iterdir()) == ["README.md", "exercises", "requirements.txt", wheel.name]
    assert "grade.py check" not in (bare / "README.md").read_text()
    assert not any("grade.py" in path.read_text() for path in (bare / "exercises").glob("ex*.py"))
    assert all("scores 0 for the exercise" in path.read_text() for path in (bare / "exercises").glob("ex*.py"))
