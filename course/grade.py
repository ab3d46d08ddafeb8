"""Grade a folder of student submissions: one pytest run of ``course/graders`` per student.

Usage (from the repository root)::

    python course/grade.py SUBMISSIONS_DIR [--out grades.json] [--exercise ex01_velocity_keypoints]
                           [-k EXPRESSION] [--jobs 2] [--timeout 600]

``SUBMISSIONS_DIR`` holds one folder per student, each with that student's ``exNN_name.py``
files. Each student is graded in a separate process (a crashing or endless submission cannot
touch the others); the table printed at the end gives passed/total tests per exercise, and
``--out`` writes, per student and exercise, the counts, every test's outcome and the failure
messages as JSON. ``--exercise`` (repeatable) grades only the named exercises: their grader modules
alone are collected, so a student is graded in the time of those graders (a few seconds) instead of
all of them.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree
from pathlib import Path

from tqdm import tqdm

from toolimit.artifacts import save_json

GRADERS = Path(__file__).resolve().parent / "graders"
SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"


#: A student's result for one exercise: {"passed": int, "total": int, "tests": {test id: outcome},
#: "messages": {test id: first lines of the failure}}; outcome is passed, failed, error or skipped.
ExerciseGrade = dict[str, object]


def exercises() -> list[str]:
    """The exercises that have a grader (``graders/test_<exercise>.py``), in order."""
    return sorted(path.stem.removeprefix("test_") for path in GRADERS.glob("test_ex*.py"))


def run_graders(
    folder: Path, keyword: str | None, timeout_s: float, selected: list[str] | None = None
) -> dict[str, ExerciseGrade]:
    """{exercise: ExerciseGrade} for one submission folder; ``selected`` exercises only, when given."""
    graders = [str(GRADERS / f"test_{exercise}.py") for exercise in selected] if selected else [str(GRADERS)]
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.xml"
        command = [sys.executable, "-m", "pytest", *graders, "-q", "-p", "no:cacheprovider", f"--junitxml={report}"]
        if keyword:
            command += ["-k", keyword]
        env = {**os.environ, SUBMISSION_ENV: str(folder.resolve())}
        try:
            subprocess.run(
                command, env=env, cwd=GRADERS.parents[1], capture_output=True, timeout=timeout_s, check=False
            )
        except subprocess.TimeoutExpired:
            return {"all": exercise_grade({"run": "error"}, {"run": f"timed out after {timeout_s:.0f} s"})}
        if not report.is_file():
            return {"all": exercise_grade({"run": "error"}, {"run": "pytest wrote no report"})}
        return parse_junit(report)


def exercise_grade(tests: dict[str, str], messages: dict[str, str]) -> ExerciseGrade:
    passed = sum(outcome == "passed" for outcome in tests.values())
    return {"passed": passed, "total": len(tests), "tests": tests, "messages": messages}


def parse_junit(report: Path) -> dict[str, ExerciseGrade]:
    """Grades by exercise (the grader module name without ``test_``) from a JUnit XML report."""
    tests: dict[str, dict[str, str]] = {}
    messages: dict[str, dict[str, str]] = {}
    for case in ElementTree.parse(report).getroot().iter("testcase"):
        module = case.get("classname", "").rsplit(".", 1)[-1]
        exercise = module.removeprefix("test_") or "collection"
        name = case.get("name", "?")
        outcome = "passed"
        for tag in ("failure", "error", "skipped"):
            element = case.find(tag)
            if element is not None:
                outcome = {"failure": "failed", "error": "error", "skipped": "skipped"}[tag]
                if tag != "skipped":
                    text = element.get("message") or element.text or ""
                    messages.setdefault(exercise, {})[name] = "\n".join(text.strip().splitlines()[:12])
                break
        tests.setdefault(exercise, {})[name] = outcome
    return {exercise: exercise_grade(tests[exercise], messages.get(exercise, {})) for exercise in tests}


def summary_table(grades: dict[str, dict[str, ExerciseGrade]]) -> str:
    """One line per student: passed/total tests of each exercise."""
    exercises = sorted({exercise for student in grades.values() for exercise in student})
    lines = ["student".ljust(24) + "".join(exercise[:24].ljust(26) for exercise in exercises)]
    for student, outcomes in grades.items():
        cells = []
        for exercise in exercises:
            grade = outcomes.get(exercise)
            cells.append((f"{grade['passed']}/{grade['total']}" if grade else "-").ljust(26))
        lines.append(student[:23].ljust(24) + "".join(cells))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submissions", type=Path, help="folder with one sub-folder per student")
    parser.add_argument("--out", type=Path, help="write every test's outcome to this JSON file")
    parser.add_argument(
        "--exercise",
        action="append",
        choices=exercises(),
        metavar="EXERCISE",
        help=f"grade only this exercise (repeatable; default: all of {', '.join(exercises())})",
    )
    parser.add_argument("-k", dest="keyword", help="pytest -k expression, e.g. ex01")
    parser.add_argument("--jobs", type=int, default=1, help="students graded at the same time (default 1)")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per student (default 600)")
    args = parser.parse_args(argv)
    if not args.submissions.is_dir():
        print(f"grade: error: {args.submissions} is not a folder", file=sys.stderr)
        return 2
    students = sorted(
        path for path in args.submissions.iterdir() if path.is_dir() and not path.name.startswith((".", "_"))
    )
    if not students:
        print(f"grade: error: {args.submissions} has no student sub-folder", file=sys.stderr)
        return 2
    if args.jobs < 1:
        print(f"grade: error: --jobs must be at least 1, got {args.jobs}", file=sys.stderr)
        return 2
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_graders, student, args.keyword, args.timeout, args.exercise) for student in students]
        results = [future.result() for future in tqdm(futures, desc="grading", unit="student")]
    grades = {student.name: result for student, result in zip(students, results)}
    print(summary_table(grades))
    if args.out:
        save_json(args.out, grades)
    return 0


if __name__ == "__main__":
    sys.exit(main())
