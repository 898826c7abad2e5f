"""The CI integration files: `.pre-commit-hooks.yaml` and the GitHub Actions
example are valid YAML, name only rcsc commands that parse, and the workflow
uses the documented actions."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
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


def _actionlint() -> str:
    """actionlint (rhysd/actionlint), which `.ci/run` installs into .tools/bin."""
    found = shutil.which("actionlint") or shutil.which("actionlint", path=str(ROOT / ".tools" / "bin"))
    assert found, "actionlint is missing: .ci/run installs it (go install github.com/rhysd/actionlint/cmd/actionlint@v1.7.12)"
    return found


def test_github_workflow_example_passes_actionlint(tmp_path: Path) -> None:
    """actionlint knows GitHub's workflow schema and the inputs of the actions
    the example uses, so a misspelt key or action input fails here."""
    proc = subprocess.run([_actionlint(), "-no-color", str(ROOT / "docs" / "examples" / "github-workflow.yml")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    # The same linter fails a misspelt action input or job key, so the pass above means something.
    for good, typo in (("python-version:", "python-versio:"), ("runs-on:", "run-on:")):
        bad = tmp_path / "bad.yml"
        bad.write_text((ROOT / "docs" / "examples" / "github-workflow.yml").read_text().replace(good, typo))
        proc = subprocess.run([_actionlint(), "-no-color", str(bad)], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 1 and good.rstrip(":") in proc.stdout, proc.stdout + proc.stderr


def _git(cwd: Path, *argv: str) -> None:
    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *argv], cwd=cwd, check=True,
                   capture_output=True, timeout=60)


def test_pre_commit_try_repo_runs_the_hooks(tmp_path: Path) -> None:
    """`pre-commit try-repo` installs rcsc from this checkout the way a user's
    `.pre-commit-config.yaml` would, and runs the hooks on example designs: the
    clean examples pass, a design with an error and an unformatted one fail."""
    project = tmp_path / "project"
    shutil.copytree(ROOT / "examples" / "submarine", project / "submarine")
    shutil.copytree(ROOT / "examples" / "machine_tool", project / "machine_tool")
    _git(project, "init", "-q")
    _git(project, "add", "-A")
    env = {**os.environ, "PRE_COMMIT_HOME": str(tmp_path / "pre-commit-home"), "PIP_DISABLE_PIP_VERSION_CHECK": "1"}
    env.pop("VIRTUAL_ENV", None)

    def try_repo(*files: Path) -> subprocess.CompletedProcess[str]:
        # No hook id: every hook of .pre-commit-hooks.yaml runs, in its order
        # (check, fmt, fmt --check), from one environment install.
        return subprocess.run([sys.executable, "-m", "pre_commit", "try-repo", str(ROOT), "--verbose",
                               "--files", *[str(f.relative_to(project)) for f in files]],
                              cwd=project, env=env, capture_output=True, text=True, timeout=900)

    proc = try_repo(*sorted(project.rglob("*.rcs")))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for hook in ("rcsc check", "rcsc fmt", "rcsc fmt --check"):
        assert re.search(rf"^{re.escape(hook)}\.+Passed$", proc.stdout, re.M), proc.stdout

    # A design with a type error, also out of the canonical layout: the check
    # fails with the diagnostic, fmt rewrites the file, and then it is formatted.
    broken = project / "submarine" / "submarine.rcs"
    broken.write_text(broken.read_text().replace("\n", "\n\n\n", 1) + "\nconst BROKEN: i32 = true\n")
    before = broken.read_text()
    proc = try_repo(broken)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert re.search(r"^rcsc check\.+Failed$", proc.stdout, re.M) and "error[E02" in proc.stdout, proc.stdout
    assert re.search(r"^rcsc fmt\.+Failed$", proc.stdout, re.M) and "files were modified by this hook" in proc.stdout
    assert broken.read_text() != before and "const BROKEN" in broken.read_text()
