"""Grade course submissions: one pytest run of an exercise's grader per student and exercise.

Usage (paths relative to where you run it; ``course/grade.py`` in the repository, ``grade.py`` in a
student bundle)::

    python course/grade.py SUBMISSIONS_DIR [--out grades.json] [--exercise ex01_velocity_keypoints]
                           [-k EXPRESSION] [--jobs 2] [--timeout 120] [--call-timeout 20]
    python course/grade.py check [FOLDER] [--exercise ex01] [--all]     # a student checks their own work
    python course/grade.py bundle OUT [--without-graders]               # what a student receives

``SUBMISSIONS_DIR`` holds one folder per student, each with that student's ``exNN_name.py``
files. Every (student, exercise) pair is graded in a separate process with its own time limit
(``--timeout`` seconds, default 120): an endless loop or a crash costs that exercise only. Inside,
each call of the student's function has ``--call-timeout`` seconds (default 20); after one ran out,
the exercise's remaining tests fail at once. A missing file is reported without starting pytest.

Each exercise gets a status: ``graded`` (passed/total tests), ``not attempted`` (the untouched stub),
``missing`` (no file), ``does not import``, ``timed out`` (0 points), or ``forbidden`` (0 points: the
submission calls an existing implementation of what it is asked to write; see
``graders/grading.py``). The table printed at the end gives one cell per student and exercise;
``--out`` writes, per student and exercise, the status, the counts, the seconds taken, every test's
outcome and the failure messages as JSON. ``--exercise`` (repeatable; ``ex01`` is enough) grades only
the named exercises.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COURSE = Path(__file__).resolve().parent
GRADERS = COURSE / "graders"
EXERCISES = COURSE / "exercises"
SOLUTIONS = COURSE / "solutions"
STUDENT_README = COURSE / "STUDENTS.md"
SUBMISSION_ENV = "TOOLIMIT_SUBMISSION"
REPORT_ENV = "TOOLIMIT_GRADE_REPORT"
CALL_LIMIT_ENV = "TOOLIMIT_CALL_TIME_LIMIT"
#: What the student bundle takes from graders/ (besides test_ex*.py).
GRADER_SUPPORT = ("conftest.py", "grading.py", "isolation.py", "student_process.py", "pytest.ini")
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
    folder: Path, exercise: str, keyword: str | None = None, timeout_s: float = 120.0, call_timeout_s: float = 20.0
) -> ExerciseGrade:
    """Run ``graders/test_<exercise>.py`` on ``folder`` in a separate process; its ExerciseGrade."""
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
            messages[name] = "\n".join(record.get("message", "").strip().splitlines()[:12])
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
    status = grade["status"]
    if status == "graded":
        return f"{grade['passed']}/{grade['total']}"
    return f"0/{grade['total']} {status}" if status in ("forbidden", "timed out") else status


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

    selected = list(dict.fromkeys(args.exercise)) if args.exercise else exercises()
    pairs = [(student, exercise) for student in students for exercise in selected]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [
            pool.submit(grade_exercise, student, exercise, args.keyword, args.timeout, args.call_timeout)
            for student, exercise in pairs
        ]
        results = [future.result() for future in tqdm(futures, desc="grading", unit="exercise")]
    grades: dict[str, dict[str, ExerciseGrade]] = {}
    for (student, exercise), result in zip(pairs, results):
        grades.setdefault(student.name, {})[exercise] = result
    print(summary_table(grades))
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(grades, indent=1) + "\n", encoding="utf-8")
    return 0


# --- one student's own check --------------------------------------------------------------------------
def check_report(grades: dict[str, ExerciseGrade], show: int | None = 3) -> str:
    """One line per exercise; under a partly failing one, its first ``show`` failures (all if None)."""
    lines = []
    for exercise, grade in grades.items():
        status = grade["status"]
        if status == "graded":
            verdict = f"{grade['passed']}/{grade['total']} tests passed" + (
                f" in {grade['seconds']:.0f} s" if grade["seconds"] >= 10 else ""
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
            lines.extend(f"    {line}" for line in message.splitlines()[:8])
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


def write_bundle(out: Path, with_graders: bool = True) -> list[Path]:
    """Write what a student receives into ``out`` (new or empty): exercises/, README.md and, with
    graders, graders/ and grade.py for self-checking. Never a solution. The files written."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise FileExistsError(f"{out} exists and is not an empty folder")
    sources = [(path, Path("exercises") / path.name) for path in sorted(EXERCISES.glob("ex*.py"))]
    if with_graders:
        sources += [(GRADERS / name, Path("graders") / name) for name in GRADER_SUPPORT]
        sources += [(path, Path("graders") / path.name) for path in sorted(GRADERS.glob("test_ex*.py"))]
        sources.append((Path(__file__).resolve(), Path("grade.py")))
    solutions = {path.read_bytes() for path in SOLUTIONS.glob("*.py")} if SOLUTIONS.is_dir() else set()
    written = []
    for source, relative in sources:
        if source.read_bytes() in solutions or "solutions" in relative.parts:
            raise RuntimeError(f"refusing to bundle {source}: it is a reference solution")
        target = out / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
        written.append(target)
    (out / "README.md").write_text(student_readme(with_graders), encoding="utf-8")
    written.append(out / "README.md")
    return written


def bundle(args: argparse.Namespace) -> int:
    try:
        written = write_bundle(args.out, not args.without_graders)
    except (FileExistsError, RuntimeError) as error:
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
        parser.add_argument("--without-graders", action="store_true", help="exercises and README only (exams)")
        return bundle(parser.parse_args(argv[1:]))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submissions", type=Path, help="folder with one sub-folder per student")
    parser.add_argument("--out", type=Path, help="write every test's outcome to this JSON file")
    parser.add_argument("--jobs", type=int, default=1, help="exercises graded at the same time (default 1)")
    add_run_options(parser)
    return grade_class(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
