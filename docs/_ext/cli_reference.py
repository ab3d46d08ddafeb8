"""The command line's reference page, generated from the ``toolimit`` command's own argparse parsers.

``{toolimit-cli}`` walks :func:`toolimit.cli.build_parser` and writes, for every sub-command (and
every action of ``toolimit demo``), its description, its usage line and a table of its flags with
its help with the default, as the parsers hold them: the page cannot drift from the code. Help texts
are shown as plain text (they are written for a terminal, not as reStructuredText).
"""

from __future__ import annotations

import argparse
from typing import Any

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The sub-parsers of ``parser`` by name, in the order they were registered."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices.items())
    return {}


def _flag_names(action: argparse.Action) -> str:
    if not action.option_strings:
        return action.metavar or action.dest  # type: ignore[return-value]
    return ", ".join(action.option_strings)


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The help text as ``toolimit CMD --help`` prints it (defaults expanded), on one line."""
    if not action.help:
        return ""
    return " ".join(parser._get_formatter()._expand_help(action).split())


def _table(parser: argparse.ArgumentParser) -> nodes.table:
    rows = [
        (
            _flag_names(action) + (f" {action.metavar}" if action.option_strings and action.metavar else ""),
            _help(parser, action),
        )
        for action in parser._actions
        if not isinstance(action, (argparse._HelpAction, argparse._SubParsersAction))
        and action.help != argparse.SUPPRESS
    ]
    table = nodes.table()
    group = nodes.tgroup(cols=2)
    table += group
    for width in (30, 70):
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    group += head
    body = nodes.tbody()
    group += body
    for cells, section in [(("flag", "what it sets (default)"), head), *[(row, body) for row in rows]]:
        row = nodes.row()
        for index, text in enumerate(cells):
            entry = nodes.entry()
            paragraph = nodes.paragraph()
            paragraph += nodes.literal(text=text) if index == 0 and section is body else nodes.Text(text)
            entry += paragraph
            row += entry
        section += row
    return table


def _section(name: str, parser: argparse.ArgumentParser, document: Any) -> nodes.section:
    section = nodes.section(ids=[nodes.make_id(name)], names=[nodes.fully_normalize_name(name)])
    section += nodes.title(text=name)
    if parser.description:
        section += nodes.paragraph(text=" ".join(parser.description.split()))
    section += nodes.literal_block(text=" ".join(parser.format_usage().split()))
    section += _table(parser)
    document.note_implicit_target(section)
    return section


class CliReference(Directive):
    """``{toolimit-cli}``: one section per sub-command of ``toolimit``."""

    def run(self) -> list[nodes.Node]:
        from toolimit.cli import build_parser

        document = self.state.document
        parser = build_parser()
        found: list[nodes.Node] = []
        for name, sub in _subcommands(parser).items():
            actions = _subcommands(sub)
            if actions:
                for action_name, action_parser in actions.items():
                    found.append(_section(f"toolimit {name} {action_name}", action_parser, document))
            else:
                found.append(_section(f"toolimit {name}", sub, document))
        return found


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("toolimit-cli", CliReference)
    return {"version": "1", "parallel_read_safe": True}
