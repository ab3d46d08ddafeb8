"""Every reference document the project cites is in the project.

The method's reference lives in ``docs/`` (``docs/method.md``, ``docs/original_setup.md``). A
tracked file may cite a ``docs/...md`` path (with an optional ``#section``) or link a markdown file
relatively; each must exist, and the section must be one of its headings. Names of documents that
live outside the project (the design notes and the authors' set-up notes the docs were written
from) must not be cited: a user's clone does not have them.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
THIS = Path(__file__).resolve()
#: Documents outside the project: citing one sends a reader nowhere.
OUTSIDE = ("AUTHORS_SETUP.md", "DESIGN.md", "ECOSYSTEM.md")
#: ``docs/x.md`` or ``docs/x.md#section`` named from the repository root (not part of a URL or path).
DOCS_PATH = re.compile(r"(?<![\w/.-])(docs/[\w./-]+?\.md)(?:#([\w-]+))?")
#: A markdown link to a local markdown file: ``[text](path.md#section)``.
MARKDOWN_LINK = re.compile(r"\]\((?!https?://)([\w./-]+?\.md)(?:#([\w-]+))?\)")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".cfg", ".ini", ".yml", ".yaml", ".json", ".ipynb", ".rst", ""}


def tracked_files() -> list[Path]:
    """The project's tracked text files (git), or every file outside hidden folders without git."""
    try:
        listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True, timeout=60)
        paths = [REPO / name for name in listed.stdout.decode().split("\0") if name]
    except (OSError, subprocess.CalledProcessError, subprocess.TimeoutExpired):
        paths = [path for path in REPO.rglob("*") if not any(part.startswith(".") for part in path.parts)]
    return [path for path in paths if path.is_file() and path.suffix in TEXT_SUFFIXES and path.resolve() != THIS]


def heading_anchors(markdown: Path) -> set[str]:
    """GitHub's anchors of a markdown file's headings: lower case, punctuation dropped, spaces -> '-'."""
    anchors = set()
    for line in markdown.read_text(encoding="utf-8").splitlines():
        match = re.match(r"#{1,6}\s+(.*)", line)
        if match:
            text = re.sub(r"[^\w\- ]", "", match.group(1).strip().lower())
            anchors.add(text.replace(" ", "-"))
    return anchors


def citations(path: Path, text: str) -> list[tuple[Path, str | None, str]]:
    """(target file, section or None, as written) for each cited document in a file's text."""
    found = [(REPO / match.group(1), match.group(2), match.group(0)) for match in DOCS_PATH.finditer(text)]
    if path.suffix == ".md":
        found += [
            ((path.parent / match.group(1)).resolve(), match.group(2), match.group(0))
            for match in MARKDOWN_LINK.finditer(text)
        ]
    return found


@pytest.fixture(scope="module")
def texts() -> dict[Path, str]:
    return {path: path.read_text(encoding="utf-8", errors="replace") for path in tracked_files()}


def test_the_method_reference_is_in_the_project():
    assert (REPO / "docs" / "method.md").is_file() and (REPO / "docs" / "original_setup.md").is_file()


def test_no_file_cites_a_document_outside_the_project(texts):
    problems = [
        f"{path.relative_to(REPO)}:{text.count(chr(10), 0, text.index(name)) + 1}: cites {name}"
        for path, text in texts.items()
        for name in OUTSIDE
        if name in text
    ]
    assert not problems, "cite docs/method.md or docs/original_setup.md instead:\n" + "\n".join(problems)


def test_every_cited_document_and_section_exists(texts):
    problems = []
    for path, text in texts.items():
        for target, section, written in citations(path, text):
            where = f"{path.relative_to(REPO)}: {written}"
            if not target.is_file():
                problems.append(f"{where}: no such file")
            elif section and section not in heading_anchors(target):
                problems.append(f"{where}: no heading #{section} in {target.relative_to(REPO)}")
    assert not problems, "\n".join(problems)


def test_the_check_sees_a_bad_citation(tmp_path):
    """The patterns find what they are meant to find (a guard against a silently empty check)."""
    text = "see docs/missing.md and docs/method.md#no-such-section, [x](docs/method.md#overview)"
    cited = {(target.name, section) for target, section, _ in citations(tmp_path / "a.md", text)}
    assert ("missing.md", None) in cited and ("method.md", "no-such-section") in cited
    assert "overview" in heading_anchors(REPO / "docs" / "method.md")
    assert not DOCS_PATH.search("https://frankaemika.github.io/docs/control_parameters.html")
