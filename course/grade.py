"""Grade course submissions: one pytest run of an exercise's grader per student and exercise, the
student's code in a process of its own (graders/isolation.py).

Usage (paths relative to where you run it; ``course/grade.py`` in the repository, ``grade.py`` in a
student bundle)::

    python course/grade.py SUBMISSIONS_DIR [--out grades.json] [--csv grades.csv] [--gradescope DIR]
                           [--hidden-seed N] [--weights weights.json] [--exercise ex01] [-k EXPRESSION]
                           [--jobs 2] [--timeout 120] [--call-timeout 20]
    python course/grade.py check [FOLDER] [--exercise ex01] [--all]     # a student checks their own work
    python course/grade.py bundle OUT [--without-graders] [--wheel W]   # what a student receives
    python course/grade.py gradescope SUBMISSION --out results.json     # one submission (run_autograder)
    python course/grade.py autograder autograder.zip [--hidden-seed N]  # Gradescope's autograder zip

``SUBMISSIONS_DIR`` holds one folder per student, each with that student's ``exNN_name.py``
files. Every (student, exercise) pair is graded in a separate process with its own time limit
(``--timeout`` seconds, default 120): an endless loop or a crash costs that exercise only. Inside,
each call of the student's function has ``--call-timeout`` seconds (default 20); after one ran out,
the exercise's remaining tests fail at once. A missing file is reported without starting pytest.

Each exercise gets a status: ``graded``, ``not attempted`` (the untouched stub), ``missing`` (no
file), ``does not import``, ``timed out`` (0 points), or ``forbidden`` (0 points: the submission
calls an existing implementation of what it is asked to write; see ``graders/grading.py``), and
points: each test group (a test function and its cases) is worth its grader's ``WEIGHTS`` (or
``--weights``), shared by its cases. ``--hidden-seed`` grades on cases drawn from the instructor's
seed instead of the public ones. The table printed at the end gives one cell per student and
exercise; ``--out`` writes every test's outcome, the messages and the points as JSON, ``--csv`` one
row per student, ``--gradescope`` Gradescope's ``results.json`` per student.
"""

from __future__ import annotations

import argparse
import ast
import concurrent.futures
import csv
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

COURSE = Path(__file__).resolve().parent
GRADERS = COURSE / "graders"
EXERCISES = COURSE / "exercises"
SOLUTIONS = COURSE / "solutions"
STUDENT_README = COURSE / "STUDENTS.md"
SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"
REPORT_ENV = "TOOLIMIT_GRADE_REPORT"
CALL_LIMIT_ENV = "TOOLIMIT_CALL_TIME_LIMIT"
HIDDEN_SEED_ENV = "TOOLIMIT_HIDDEN_SEED"
#: What the student bundle takes from graders/ (besides test_ex*.py).
GRADER_SUPPORT = ("conftest.py", "grading.py", "isolation.py", "student_process.py", "pytest.ini")
#: The notebooks whose exercise cells the bundle carries (solutions stripped) and the data they read.
NOTEBOOKS = COURSE.parent / "notebooks"
NOTEBOOK_DATA = COURSE.parent / "data" / "demos"
#: A solution inside a notebook's code cell: the lines between these markers (nbgrader's syntax),
#: replaced in the bundle by one line raising NotImplementedError.
SOLUTION_START, SOLUTION_END = "### BEGIN SOLUTION", "### END SOLUTION"
#: Lines of a failure message kept (grades.json) and shown (the self-check): the graders keep theirs
#: shorter, so the line that explains the failure is never cut.
MESSAGE_LINES = 12
#: Lines of STUDENTS.md between these markers are about self-checking (dropped without graders).
SELF_CHECK_START, SELF_CHECK_END = "<!-- self-check -->", "<!-- /self-check -->"

#: A student's result for one exercise: {"status": str, "passed": int, "total": int, "seconds": float,
#: "tests": {test id: outcome}, "messages": {test id: failure message}}; outcome is passed, failed,
#: error or skipped.
ExerciseGrade = dict[str, object]


def exercises() -> list[str]:
    """The exercises that have a grader (``graders/test_<exercise>.py``), in order."""
    return sorted(path.stem.removeprefix("test_") for path in GRADERS.glob("test_ex*.py"))


def exercise_name(value: str) -> str:
    """``ex01`` or ``ex01_velocity_keypoints`` -> ``ex01_velocity_keypoints`` (argparse type)."""
    matches = [name for name in exercises() if name == value or name.split("_", 1)[0] == value]
    if len(matches) != 1:
        raise argparse.ArgumentTypeError(f"invalid choice: {value!r} (choose from {', '.join(exercises())})")
    return matches[0]


# --- one exercise of one student -------------------------------------------------------------------
def grade_exercise(
    folder: Path,
    exercise: str,
    keyword: str | None = None,
    timeout_s: float = 120.0,
    call_timeout_s: float = 20.0,
    hidden_seed: int | None = None,
    weights: dict[str, float] | None = None,
) -> ExerciseGrade:
    """Run ``graders/test_<exercise>.py`` on ``folder`` in a separate process (the student's code in
    a third one); its ExerciseGrade, scored with ``weights`` (default: the grader's ``WEIGHTS``)."""
    grade = run_grader(folder, exercise, keyword, timeout_s, call_timeout_s, hidden_seed)
    return scored(grade, grader_weights(exercise) if weights is None else weights)


def run_grader(
    folder: Path, exercise: str, keyword: str | None, timeout_s: float, call_timeout_s: float, hidden_seed: int | None
) -> ExerciseGrade:
    started = time.perf_counter()
    if not (folder / f"{exercise}.py").is_file():
        message = f"no file {exercise}.py in the submission folder {folder}"
        return finish({}, {"run": message}, {}, "missing", started)
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.jsonl"
        command = [sys.executable, "-m", "pytest", str(GRADERS / f"test_{exercise}.py"), "-q", "-p", "no:cacheprovider"]
        if keyword:
            command += ["-k", keyword]
        env = {
            **os.environ,
            SUBMISSION_ENV: str(folder.resolve()),
            REPORT_ENV: str(report),
            CALL_LIMIT_ENV: str(call_timeout_s),
        }
        env.pop(HIDDEN_SEED_ENV, None)
        if hidden_seed is not None:
            env[HIDDEN_SEED_ENV] = str(hidden_seed)
        process = subprocess.Popen(
            command,
            env=env,
            cwd=COURSE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,  # its own process group: a timeout kills whatever it started
        )
        try:
            output, _ = process.communicate(timeout=timeout_s)
            timed_out = False
        except subprocess.TimeoutExpired:
            if hasattr(os, "killpg"):
                os.killpg(process.pid, signal.SIGKILL)
            else:  # Windows: no process groups here
                process.kill()
            output, _ = process.communicate()
            timed_out = True
        records = read_report(report)
    tests, messages, verdicts, collected = collect(records)
    if timed_out:
        message = f"stopped after {timeout_s:g} s (an endless loop?), {len(tests)} of {collected} tests finished"
        total = max(collected, len(tests))
        return finish(tests, {"run": message, **messages}, verdicts, "timed out", started, total=total)
    if not tests:
        tail = "\n".join(output.strip().splitlines()[-12:])
        return finish({"run": "error"}, {"run": f"the grader did not run:\n{tail}"}, {}, "error", started)
    return finish(tests, messages, verdicts, status_of(verdicts, tests), started)


def read_report(path: Path) -> list[dict]:
    if not path.is_file():
        return []
    records = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:  # a line cut by a kill
            continue
    return records


def collect(records: list[dict]) -> tuple[dict[str, str], dict[str, str], dict[str, str], int]:
    """(outcomes, messages, verdicts, number collected) per test name from the report's records."""
    tests: dict[str, str] = {}
    messages: dict[str, str] = {}
    verdicts: dict[str, str] = {}
    collected = 0
    for record in records:
        if "collected" in record:
            collected = int(record["collected"])
            continue
        name = record["test"].split("::")[-1]
        when, outcome = record["when"], record["outcome"]
        if when == "call":
            tests[name] = {"passed": "passed", "failed": "failed", "skipped": "skipped"}[outcome]
        elif outcome == "failed":  # setup, teardown or collection
            tests[name] = "error"
        elif outcome == "skipped":
            tests.setdefault(name, "skipped")
        if outcome == "failed" and name not in messages:
            messages[name] = "\n".join(record.get("message", "").strip().splitlines()[:MESSAGE_LINES])
            verdicts[name] = record.get("verdict") or "failed"
    return tests, messages, verdicts, collected


def status_of(verdicts: dict[str, str], tests: dict[str, str]) -> str:
    kinds = set(verdicts.values())
    failed_all = len(verdicts) == len(tests)
    if "forbidden" in kinds:
        return "forbidden"
    if failed_all and kinds == {"not_written"}:
        return "not attempted"
    if failed_all and kinds == {"import_error"}:
        return "does not import"
    return "graded"


def finish(
    tests: dict[str, str],
    messages: dict[str, str],
    verdicts: dict[str, str],
    status: str,
    started: float,
    total: int | None = None,
) -> ExerciseGrade:
    passed = sum(outcome == "passed" for outcome in tests.values())
    if status in ("forbidden", "timed out"):
        passed = 0  # the whole exercise: a shortcut or a loop in one test voids the others
    return {
        "status": status,
        "passed": passed,
        "total": len(tests) if total is None else total,
        "seconds": round(time.perf_counter() - started, 2),
        "tests": tests,
        "messages": messages,
        "verdicts": verdicts,
    }


# --- points ----------------------------------------------------------------------------------------
def group_of(test: str) -> str:
    """The test group of a test id: its function's name (``test_ex01_x[3-0.05]`` -> ``test_ex01_x``)."""
    return test.split("[", 1)[0]


def grader_weights(exercise: str) -> dict[str, float]:
    """The points of each test group of an exercise: the grader's ``WEIGHTS`` literal (read, not
    imported); a group it does not name is worth 1 point."""
    tree = ast.parse((GRADERS / f"test_{exercise}.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(target, "id", None) == "WEIGHTS" for target in node.targets):
            return {str(name): float(points) for name, points in ast.literal_eval(node.value).items()}
    return {}


def scored(grade: ExerciseGrade, weights: dict[str, float]) -> ExerciseGrade:
    """The grade with ``score`` and ``max_score``: each test group is worth its weight, shared by
    its cases (the share of passed cases earns that share of the points); a forbidden or timed-out
    exercise scores 0. ``groups``: {group: [score, max_score]}."""
    tests: dict[str, str] = grade["tests"]  # type: ignore[assignment]
    groups: dict[str, list[str]] = {}
    for test, outcome in tests.items():
        if test != "run":
            groups.setdefault(group_of(test), []).append(outcome)
    points = {}
    for group, outcomes in groups.items():
        weight = weights.get(group, 1.0)
        earned = weight * sum(outcome == "passed" for outcome in outcomes) / len(outcomes)
        points[group] = [round(earned, 4), weight]
    if grade["status"] in ("forbidden", "timed out"):
        points = {group: [0.0, weight] for group, (_, weight) in points.items()}
    unnamed = {group for group in points if group not in weights}  # a test the WEIGHTS do not name: 1 point
    max_score = sum(weights.values()) + len(unnamed) or 1.0
    return {
        **grade,
        "score": round(sum(earned for earned, _ in points.values()), 4),
        "max_score": max_score,
        "groups": points,
    }


def headline(grade: ExerciseGrade) -> str:
    """The one message that explains a forbidden, timed-out or unreadable exercise, or ''."""
    messages = grade["messages"]
    if grade["status"] == "forbidden":
        return next(messages[name] for name, verdict in grade["verdicts"].items() if verdict == "forbidden")
    if grade["status"] in ("timed out", "missing", "error"):
        return messages.get("run", "")
    if grade["status"] == "does not import":
        return next(iter(messages.values()), "")
    return ""


def cell(grade: ExerciseGrade | None) -> str:
    if grade is None:
        return "-"
    status, points = grade["status"], f"{grade['score']:g}/{grade['max_score']:g}"
    if status == "graded":
        return f"{points} ({grade['passed']}/{grade['total']} tests)"
    return f"{points} {status}"


# --- a class ----------------------------------------------------------------------------------------
def summary_table(grades: dict[str, dict[str, ExerciseGrade]]) -> str:
    """One line per student: passed/total tests of each exercise, or why there are none."""
    names = sorted({exercise for student in grades.values() for exercise in student})
    lines = ["student".ljust(24) + "".join(exercise[:24].ljust(26) for exercise in names)]
    for student, outcomes in grades.items():
        lines.append(student[:23].ljust(24) + "".join(cell(outcomes.get(exercise)).ljust(26) for exercise in names))
    notes = [
        f"{student} {exercise}: {headline(grade).splitlines()[0]}"
        for student, outcomes in grades.items()
        for exercise, grade in outcomes.items()
        if grade["status"] in ("forbidden", "timed out", "error") and headline(grade)
    ]
    return "\n".join(lines + ([""] + notes if notes else []))


def grade_class(args: argparse.Namespace) -> int:
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
    from tqdm import tqdm

    try:
        weights = read_weights(args.weights)
    except ValueError as error:
        print(f"grade: error: {error}", file=sys.stderr)
        return 2
    selected = list(dict.fromkeys(args.exercise)) if args.exercise else exercises()
    pairs = [(student, exercise) for student in students for exercise in selected]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [
            pool.submit(
                grade_exercise,
                student,
                exercise,
                args.keyword,
                args.timeout,
                args.call_timeout,
                args.hidden_seed,
                weights.get(exercise),
            )
            for student, exercise in pairs
        ]
        results = [future.result() for future in tqdm(futures, desc="grading", unit="exercise")]
    grades: dict[str, dict[str, ExerciseGrade]] = {}
    for (student, exercise), result in zip(pairs, results):
        grades.setdefault(student.name, {})[exercise] = result
    print(summary_table(grades))
    if args.out:
        write_text(args.out, json.dumps(grades, indent=1) + "\n")
    if args.csv:
        write_text(args.csv, grades_csv(grades))
    if args.gradescope:
        for student, outcomes in grades.items():
            write_text(args.gradescope / student / "results.json", json.dumps(gradescope_results(outcomes), indent=1))
    return 0


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole (a temporary file renamed: never half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_text(text, encoding="utf-8")
    partial.replace(path)


def read_weights(path: Path | None) -> dict[str, dict[str, float]]:
    """An instructor's points per test group, ``{"ex01": {"test_ex01_keypoints_match_reference": 6}}``
    (exercise by its short or full name); groups left out keep the grader's ``WEIGHTS``."""
    if path is None:
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as error:
        raise ValueError(f"--weights {path}: {error}") from None
    if not isinstance(data, dict):
        raise ValueError(f"--weights {path}: expected a JSON object {{exercise: {{test group: points}}}}")
    weights: dict[str, dict[str, float]] = {}
    for name, groups in data.items():
        try:
            exercise = exercise_name(str(name))
        except argparse.ArgumentTypeError as error:
            raise ValueError(f"--weights {path}: {error}") from None
        known = grader_weights(exercise)
        if not isinstance(groups, dict) or not all(isinstance(v, (int, float)) and v >= 0 for v in groups.values()):
            raise ValueError(f"--weights {path}: {name} must map test groups to non-negative points")
        unknown = sorted(set(groups) - set(known))
        if unknown:
            raise ValueError(f"--weights {path}: {name} has no test group {unknown[0]} (groups: {', '.join(known)})")
        weights[exercise] = {**known, **{str(group): float(points) for group, points in groups.items()}}
    return weights


def grades_csv(grades: dict[str, dict[str, ExerciseGrade]]) -> str:
    """One row per student: the points of each exercise, the total and the maximum (an LMS import)."""
    names = sorted({exercise for student in grades.values() for exercise in student})
    lines = io.StringIO()
    writer = csv.writer(lines, lineterminator="\n")
    writer.writerow(["student", *names, "total", "max_total"])
    for student, outcomes in grades.items():
        row = [f"{outcomes[name]['score']:g}" if name in outcomes else "" for name in names]
        total = sum(float(grade["score"]) for grade in outcomes.values())
        maximum = sum(float(grade["max_score"]) for grade in outcomes.values())
        writer.writerow([student, *row, f"{total:g}", f"{maximum:g}"])
    return lines.getvalue()


def gradescope_results(outcomes: dict[str, ExerciseGrade]) -> dict:
    """One submission's results in Gradescope's autograder format (``results.json``,
    https://gradescope-autograders.readthedocs.io/en/latest/specs/): one Gradescope test per test
    group, its points and the first failure messages."""
    tests = []
    for number, (exercise, grade) in enumerate(outcomes.items(), start=1):
        groups: dict[str, list[float]] = grade["groups"]  # type: ignore[assignment]
        messages: dict[str, str] = grade["messages"]  # type: ignore[assignment]
        note = headline(grade)
        if not groups:
            tests.append(
                {
                    "name": f"{exercise}: {grade['status']}",
                    "number": f"{number}",
                    "score": 0.0,
                    "max_score": float(grade["max_score"]),
                    "status": "failed",
                    "output": note or str(grade["status"]),
                    "visibility": "visible",
                }
            )
            continue
        for index, (group, (earned, weight)) in enumerate(groups.items(), start=1):
            failures = [message for test, message in messages.items() if group_of(test) == group]
            output = "\n\n".join(([note] if note else []) + failures[:3]) or "passed"
            tests.append(
                {
                    "name": f"{exercise}: {group.removeprefix('test_')}",
                    "number": f"{number}.{index}",
                    "score": float(earned),
                    "max_score": float(weight),
                    "status": "passed" if earned >= weight else "failed",
                    "output": output,
                    "visibility": "visible",
                }
            )
    return {
        "score": round(sum(float(grade["score"]) for grade in outcomes.values()), 4),
        "execution_time": round(sum(float(grade["seconds"]) for grade in outcomes.values())),
        "output": "\n".join(f"{exercise}: {cell(grade)}" for exercise, grade in outcomes.items()),
        "stdout_visibility": "hidden",
        "tests": tests,
    }


# --- one student's own check --------------------------------------------------------------------------
def check_report(grades: dict[str, ExerciseGrade], show: int | None = 3) -> str:
    """One line per exercise; under a partly failing one, its first ``show`` failures (all if None)."""
    lines = []
    for exercise, grade in grades.items():
        status = grade["status"]
        if status == "graded":
            verdict = (
                f"{grade['score']:g}/{grade['max_score']:g} points, {grade['passed']}/{grade['total']} tests passed"
                + (f" in {grade['seconds']:.0f} s" if grade["seconds"] >= 10 else "")
            )
        elif status in ("forbidden", "timed out"):
            verdict = f"0 points ({status}): {headline(grade)}"
        elif status in ("missing", "does not import", "error"):
            verdict = f"{status}: {headline(grade)}"
        else:
            verdict = status
        lines.append(f"{exercise:<26}{verdict}")
        if status != "graded" or grade["passed"] == grade["total"]:
            continue
        failures = [
            (name, message) for name, message in grade["messages"].items() if grade["tests"].get(name) != "passed"
        ]
        for name, message in failures[:show]:
            lines.append(f"  {name}:")
            lines.extend(f"    {line}" for line in message.splitlines()[:MESSAGE_LINES])
        if show is not None and len(failures) > show:
            short = exercise.split("_", 1)[0]
            lines.append(
                f"  ... {len(failures) - show} more failing tests (add `--exercise {short} --all` to see them)"
            )
    return "\n".join(lines)


def check_own(args: argparse.Namespace) -> int:
    folder = args.folder or EXERCISES
    if not folder.is_dir():
        print(f"grade check: error: {folder} is not a folder", file=sys.stderr)
        return 2
    selected = list(dict.fromkeys(args.exercise)) if args.exercise else exercises()
    grades = {}
    for exercise in selected:
        grades[exercise] = grade_exercise(folder, exercise, args.keyword, args.timeout, args.call_timeout)
        print(check_report({exercise: grades[exercise]}, None if args.all else 3), flush=True)
    return 0


# --- Gradescope ----------------------------------------------------------------------------------------
def grade_for_gradescope(args: argparse.Namespace) -> int:
    """Grade one submission folder on the selected exercises and write Gradescope's results.json."""
    if not args.submission.is_dir():
        print(f"grade gradescope: error: {args.submission} is not a folder", file=sys.stderr)
        return 2
    try:
        weights = read_weights(args.weights)
    except ValueError as error:
        print(f"grade gradescope: error: {error}", file=sys.stderr)
        return 2
    selected = list(dict.fromkeys(args.exercise)) if args.exercise else exercises()
    outcomes = {
        exercise: grade_exercise(
            args.submission,
            exercise,
            args.keyword,
            args.timeout,
            args.call_timeout,
            args.hidden_seed,
            weights.get(exercise),
        )
        for exercise in selected
    }
    write_text(args.out, json.dumps(gradescope_results(outcomes), indent=1))
    print("\n".join(f"{exercise}: {cell(grade)}" for exercise, grade in outcomes.items()))
    return 0


AUTOGRADER_SETUP = """#!/usr/bin/env bash
# Gradescope runs this once when it builds the autograder's image (written by grade.py autograder).
set -euo pipefail
apt-get update && apt-get install -y python3 python3-venv python3-pip
python3 -m venv /autograder/venv
/autograder/venv/bin/pip install torch==2.13.0
/autograder/venv/bin/pip install "/autograder/source/{wheel}[course]"
"""
AUTOGRADER_RUN = """#!/usr/bin/env bash
# Gradescope runs this for every submission (written by grade.py autograder).
cd /autograder/source
/autograder/venv/bin/python grade.py gradescope /autograder/submission --out /autograder/results/results.json {options}
"""


def build_wheel(out: Path) -> Path:
    """Build toolimit's wheel from the project around this course folder into ``out``: the package
    only (never course/, so never a solution)."""
    project = COURSE.parent
    if not (project / "pyproject.toml").is_file():
        raise FileNotFoundError(f"no pyproject.toml in {project}: build the wheel from the project's repository")
    out.mkdir(parents=True, exist_ok=True)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(out), str(project)],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    (wheel,) = sorted(out.glob("toolimit-*.whl"))
    return wheel


def autograder(args: argparse.Namespace) -> int:
    """Write Gradescope's autograder zip: setup.sh, run_autograder, grade.py, graders/ and toolimit's
    wheel; the hidden seed and weights (if given) are baked into run_autograder."""
    if args.out.exists():
        print(f"grade autograder: error: {args.out} exists", file=sys.stderr)
        return 2
    try:
        weights = read_weights(args.weights)
    except ValueError as error:
        print(f"grade autograder: error: {error}", file=sys.stderr)
        return 2
    options = [f"--timeout {args.timeout:g}", f"--call-timeout {args.call_timeout:g}"]
    options += [f"--exercise {exercise}" for exercise in dict.fromkeys(args.exercise or [])]
    if args.hidden_seed is not None:
        options.append(f"--hidden-seed {args.hidden_seed}")
    if weights:
        options.append("--weights weights.json")
    with tempfile.TemporaryDirectory() as tmp:
        try:
            wheel = build_wheel(Path(tmp))
        except (FileNotFoundError, subprocess.CalledProcessError) as error:
            print(f"grade autograder: error: {error}", file=sys.stderr)
            return 2
        files: dict[str, bytes] = {
            "setup.sh": AUTOGRADER_SETUP.format(wheel=wheel.name).encode(),
            "run_autograder": AUTOGRADER_RUN.format(options=" ".join(options)).encode(),
            "grade.py": Path(__file__).resolve().read_bytes(),
            wheel.name: wheel.read_bytes(),
        }
        if weights:
            files["weights.json"] = json.dumps(weights, indent=1).encode()
        for name in GRADER_SUPPORT:
            files[f"graders/{name}"] = (GRADERS / name).read_bytes()
        for path in sorted(GRADERS.glob("test_ex*.py")):
            files[f"graders/{path.name}"] = path.read_bytes()
        args.out.parent.mkdir(parents=True, exist_ok=True)
        partial = args.out.with_name(args.out.name + ".partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for name, data in files.items():
                info = zipfile.ZipInfo(name)
                info.external_attr = (0o755 if name in ("setup.sh", "run_autograder") else 0o644) << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(info, data)
        partial.replace(args.out)
    print(f"wrote {args.out}: {', '.join(files)}")
    return 0


# --- the student bundle --------------------------------------------------------------------------------
def student_readme(with_graders: bool) -> str:
    text = STUDENT_README.read_text(encoding="utf-8")
    if with_graders:
        return text.replace(SELF_CHECK_START + "\n", "").replace(SELF_CHECK_END + "\n", "")
    kept, skipping = [], False
    for line in text.splitlines(keepends=True):
        if line.strip() == SELF_CHECK_START:
            skipping = True
        elif line.strip() == SELF_CHECK_END:
            skipping = False
        elif not skipping:
            kept.append(line)
    return "".join(kept)


#: The exercises' sentence pointing at the self-check, dropped from an exam bundle (no grade.py there).
SELF_CHECK_SENTENCE = re.compile(r"Check your work with ``python grade\.py check.*?see README\.md\. ", re.DOTALL)


def exam_exercise(text: str) -> str:
    """An exercise file for a bundle without graders: the pointer to the self-check removed."""
    return SELF_CHECK_SENTENCE.sub("", text, count=1)


def strip_solutions(source: str) -> str:
    """A code cell's source with each marked solution replaced by ``raise NotImplementedError``
    (at the start marker's indentation); ValueError for a start marker without its end."""
    kept: list[str] = []
    inside = False
    for line in source.splitlines(keepends=True):
        if line.strip() == SOLUTION_START:
            indent = line[: len(line) - len(line.lstrip())]
            kept.append(f'{indent}raise NotImplementedError("exercise: write this part")\n')
            inside = True
        elif line.strip() == SOLUTION_END:
            inside = False
        elif not inside:
            kept.append(line)
    if inside:
        raise ValueError(f"a {SOLUTION_START!r} without its {SOLUTION_END!r}")
    return "".join(kept)


def student_notebook(path: Path) -> str:
    """The notebook as a student receives it: marked solutions stripped, no outputs (JSON text)."""
    notebook = json.loads(path.read_text(encoding="utf-8"))
    for cell in notebook["cells"]:
        if cell["cell_type"] != "code":
            continue
        source = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        try:
            stripped = strip_solutions(source)
        except ValueError as error:
            raise RuntimeError(f"{path.name}: {error}") from None
        cell["source"] = stripped.splitlines(keepends=True)
        cell["outputs"], cell["execution_count"] = [], None
    return json.dumps(notebook, indent=1, ensure_ascii=False) + "\n"


def exercise_notebooks() -> list[Path]:
    """The project's notebooks that hold a marked solution (the course's notebook exercises)."""
    if not NOTEBOOKS.is_dir():
        return []
    return [path for path in sorted(NOTEBOOKS.glob("*.ipynb")) if SOLUTION_START in path.read_text(encoding="utf-8")]


def write_bundle(out: Path, with_graders: bool = True, wheel: Path | None = None) -> list[Path]:
    """Write what a student receives into ``out`` (new or empty): exercises/, README.md, toolimit's
    wheel and requirements.txt (``pip install -r requirements.txt``: torch, toolimit and the
    ``course`` extra, pytest among it) and, with graders, graders/ and grade.py for self-checking,
    and the exercise notebooks (solutions stripped) with notebook_checks.py and data/demos.
    Never a solution; written beside ``out`` and renamed, so never half a bundle. The files written."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise FileExistsError(f"{out} exists and is not an empty folder")
    sources = [(path, Path("exercises") / path.name) for path in sorted(EXERCISES.glob("ex*.py"))]
    if with_graders:
        sources += [(GRADERS / name, Path("graders") / name) for name in GRADER_SUPPORT]
        sources += [(path, Path("graders") / path.name) for path in sorted(GRADERS.glob("test_ex*.py"))]
        sources.append((Path(__file__).resolve(), Path("grade.py")))
    solutions = {path.read_bytes() for path in SOLUTIONS.glob("*.py")} if SOLUTIONS.is_dir() else set()
    partial = out.with_name(out.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    try:
        for source, relative in sources:
            if source.read_bytes() in solutions or "solutions" in relative.parts:
                raise RuntimeError(f"refusing to bundle {source}: it is a reference solution")
            target = partial / relative
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
            if not with_graders and relative.parts[0] == "exercises":
                target.write_text(exam_exercise(source.read_text(encoding="utf-8")), encoding="utf-8")
        notebooks = exercise_notebooks() if with_graders else []  # an exam's bundle: no instant feedback
        for path in notebooks:
            (partial / "notebooks").mkdir(exist_ok=True)
            (partial / "notebooks" / path.name).write_text(student_notebook(path), encoding="utf-8")
        if notebooks:  # their checks (exercise 03's reads its grader's reference QP) and the data they read
            shutil.copy2(COURSE / "notebook_checks.py", partial / "notebook_checks.py")
            shutil.copytree(NOTEBOOK_DATA, partial / "data" / "demos")
        wheel = build_wheel(partial) if wheel is None else Path(shutil.copy2(wheel, partial / wheel.name))
        (partial / "requirements.txt").write_text(
            "# pip install -r requirements.txt (from this folder): torch's CPU build first, then toolimit and\n"
            "# what the course needs (pytest, jupyterlab)\n"
            f"torch==2.13.0\n./{wheel.name}[course]\n",
            encoding="utf-8",
        )
        (partial / "README.md").write_text(student_readme(with_graders), encoding="utf-8")
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    if out.exists():
        out.rmdir()
    partial.rename(out)
    return sorted(path for path in out.rglob("*") if path.is_file())


def bundle(args: argparse.Namespace) -> int:
    try:
        written = write_bundle(args.out, not args.without_graders, args.wheel)
    except (FileExistsError, FileNotFoundError, RuntimeError, subprocess.CalledProcessError) as error:
        print(f"grade bundle: error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {len(written)} files to {args.out} (no solutions):")
    for path in written:
        print(f"  {path.relative_to(args.out)}")
    return 0


# --- command line ----------------------------------------------------------------------------------------
def add_run_options(parser: argparse.ArgumentParser, timeout: float = 120.0) -> None:
    parser.add_argument(
        "--exercise",
        action="append",
        type=exercise_name,
        metavar="EXERCISE",
        help=f"grade only this exercise, e.g. ex01 (repeatable; default: all of {', '.join(exercises())})",
    )
    parser.add_argument("-k", dest="keyword", help="pytest -k expression within the exercises")
    parser.add_argument(
        "--timeout", type=float, default=timeout, help=f"seconds per exercise and student (default {timeout:g})"
    )
    parser.add_argument(
        "--call-timeout", type=float, default=20.0, help="seconds per call of a student's function (default 20)"
    )


def add_instructor_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--hidden-seed",
        type=int,
        metavar="N",
        help="grade on hidden cases drawn from this seed instead of the public ones the students check against",
    )
    parser.add_argument(
        "--weights", type=Path, metavar="JSON", help='points per test group, {"ex01": {"test_ex01_...": 6}}'
    )


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["check"]:
        parser = argparse.ArgumentParser(prog="grade.py check", description="Check your own exercises.")
        parser.add_argument("folder", type=Path, nargs="?", help=f"your exercises (default {EXERCISES})")
        parser.add_argument("--all", action="store_true", help="show every failing test, not the first three")
        add_run_options(parser)
        return check_own(parser.parse_args(argv[1:]))
    if argv[:1] == ["bundle"]:
        parser = argparse.ArgumentParser(prog="grade.py bundle", description="Write the student bundle.")
        parser.add_argument("out", type=Path, help="a new (or empty) folder")
        parser.add_argument("--without-graders", action="store_true", help="no graders, no self-check (exams)")
        parser.add_argument("--wheel", type=Path, help="toolimit's wheel to include (default: built from the project)")
        return bundle(parser.parse_args(argv[1:]))
    if argv[:1] == ["gradescope"]:
        parser = argparse.ArgumentParser(prog="grade.py gradescope", description="Grade one submission for Gradescope.")
        parser.add_argument("submission", type=Path, help="one student's folder (Gradescope: /autograder/submission)")
        parser.add_argument("--out", type=Path, required=True, help="the results.json to write")
        add_run_options(parser)
        add_instructor_options(parser)
        return grade_for_gradescope(parser.parse_args(argv[1:]))
    if argv[:1] == ["autograder"]:
        parser = argparse.ArgumentParser(prog="grade.py autograder", description="Build Gradescope's autograder zip.")
        parser.add_argument("out", type=Path, help="the zip to write, e.g. autograder.zip")
        add_run_options(parser)
        add_instructor_options(parser)
        return autograder(parser.parse_args(argv[1:]))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submissions", type=Path, help="folder with one sub-folder per student")
    parser.add_argument("--out", type=Path, help="write every test's outcome to this JSON file")
    parser.add_argument("--csv", type=Path, help="write one row per student (points per exercise, total) to this CSV")
    parser.add_argument("--gradescope", type=Path, metavar="DIR", help="write DIR/<student>/results.json (Gradescope)")
    parser.add_argument("--jobs", type=int, default=1, help="exercises graded at the same time (default 1)")
    add_run_options(parser)
    add_instructor_options(parser)
    return grade_class(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
