"""The CI integration files: `.pre-commit-hooks.yaml` and the GitHub Actions
example are valid YAML, name only rcsc commands that parse, and the workflow
uses the documented actions."""

from __future__ import annotations

import shlex
from pathlib import Path

import yaml

from rcsc import cli

ROOT = Path(__file__).resolve().parent.parent


def _parses(argv: list[str]) -> None:
    parser = cli.build_parser()
    args = parser.parse_args(argv)
    assert args.command in cli.COMMANDS


def test_pre_commit_hooks() -> None:
    hooks = yaml.safe_load((ROOT / ".pre-commit-hooks.yaml").read_text())
    assert [h["id"] for h in hooks] == ["rcsc-check", "rcsc-fmt", "rcsc-fmt-check"]
    for hook in hooks:
        assert {"id", "name", "entry", "language", "files"} <= set(hook)
        assert hook["language"] == "python" and hook["files"] == r"\.rcs$"
        argv = shlex.split(hook["entry"])[1:] + list(hook.get("args", [])) + ["x.rcs"]  # pre-commit appends the files
        assert shlex.split(hook["entry"])[0] == "rcsc"
        _parses(argv)


def test_github_workflow_example() -> None:
    wf = yaml.safe_load((ROOT / "docs" / "examples" / "github-workflow.yml").read_text())
    # PyYAML reads the key `on` as True (YAML 1.1); GitHub reads it as "on".
    assert set(wf.get("on", wf.get(True))) == {"push", "pull_request"}
    assert wf["permissions"]["security-events"] == "write"
    steps = wf["jobs"]["check"]["steps"]
    uses = [s["uses"] for s in steps if "uses" in s]
    assert uses == ["actions/checkout@v4", "actions/setup-python@v5", "github/codeql-action/upload-sarif@v3"]
    upload = next(s for s in steps if s.get("uses", "").startswith("github/codeql-action/upload-sarif"))
    sarif_step = next(s for s in steps if "--format sarif" in s.get("run", ""))
    assert upload["with"]["sarif_file"] in sarif_step["run"] and upload["if"] == "always()"
    runs = [s["run"] for s in steps if s.get("run", "").startswith("rcsc ")]
    assert len(runs) == 4
    for run in runs:
        _parses(shlex.split(run)[1:])
