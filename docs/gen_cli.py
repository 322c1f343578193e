"""Writes reference/cli.md at build time from the `srdda` command itself (mkdocs-gen-files).

The command group is found through `srdda.__main__` (what `python -m srdda` runs), not by the module
path of the CLI, so the page follows the program wherever its code lives and cannot drift from it:
each section is the `--help` text click prints for that command.
"""
from __future__ import annotations

import importlib

import click
import mkdocs_gen_files

main: click.Group = importlib.import_module("srdda.__main__").main


WIDTH = {"terminal_width": 100, "max_content_width": 100}  # fixed, so the page does not depend on the terminal
GROUP = click.Context(main, info_name="srdda", **main.context_settings, **WIDTH)


def _help(command: click.Command, name: str) -> str:
    """The help text `srdda NAME --help` prints (the group's settings, such as `-h`, inherited as in a run)."""
    return command.get_help(click.Context(command, info_name=name, parent=GROUP, **command.context_settings, **WIDTH))


lines = ["# CLI reference", "",
         "Generated when the manual is built, from the `srdda` program itself: each section is what",
         "`srdda COMMAND --help` prints. The guide to the commands, with examples and exit codes, is",
         "[Command line](../cli.md).", "", "## `srdda`", "", "```text",
         main.get_help(GROUP),
         "```", ""]
for name in sorted(main.commands):
    lines += [f"## `srdda {name}`", "", "```text", _help(main.commands[name], name), "```", ""]

with mkdocs_gen_files.open("reference/cli.md", "w") as page:
    page.write("\n".join(lines))
