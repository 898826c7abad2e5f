"""`rcsc completion SHELL`: scripts generated from the argument parser.

The bash script is run in a real bash (source it, set COMP_WORDS, call the
function, read COMPREPLY); the zsh and fish scripts are checked to name every
command and option of the parser (and, when those shells are installed, to
parse)."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from rcsc import cli

from rcsc.editor import completion
from rcsc.codes import CODES


def _script(shell: str, capsys) -> str:
    assert cli.main(["completion", shell]) == 0
    return capsys.readouterr().out


def _bash_complete(script: str, words: list[str], tmp_path) -> list[str]:
    (tmp_path / "c.bash").write_text(script)
    cword = len(words) - 1
    arr = " ".join("'" + w + "'" for w in words)
    prog = f'source {tmp_path / "c.bash"}; COMP_WORDS=({arr}); COMP_CWORD={cword}; _rcsc; printf "%s\\n" "${{COMPREPLY[@]}}"'
    out = subprocess.run(["bash", "-c", prog], capture_output=True, text=True, cwd=tmp_path, check=True)
    return [line for line in out.stdout.splitlines() if line]


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_bash_completes_commands_options_choices_codes_and_files(tmp_path, capsys) -> None:
    script = _script("bash", capsys)
    assert subprocess.run(["bash", "-n"], input=script, text=True).returncode == 0
    assert _bash_complete(script, ["rcsc", "ch"], tmp_path) == ["check"]
    assert set(_bash_complete(script, ["rcsc", ""], tmp_path)) >= set(cli.COMMANDS)
    assert _bash_complete(script, ["rcsc", "check", "--form"], tmp_path) == ["--format"]
    assert _bash_complete(script, ["rcsc", "check", "--format", "s"], tmp_path) == ["short", "sarif"]
    assert _bash_complete(script, ["rcsc", "explain", "E050"], tmp_path) == sorted(c for c in CODES if c.startswith("E050"))
    assert _bash_complete(script, ["rcsc", "build", "x", "--target", ""], tmp_path) == ["ada", "c", "rust"]
    (tmp_path / "ship.rcs").write_text("design ship\n")
    assert _bash_complete(script, ["rcsc", "check", "sh"], tmp_path) == ["ship.rcs"]
    assert _bash_complete(script, ["rcsc", "check", "--select", ""], tmp_path) == []


@pytest.mark.parametrize("shell", completion.SHELLS)
def test_every_command_and_option_is_in_the_script(shell, capsys) -> None:
    script = _script(shell, capsys)
    parser = cli.build_parser()
    _, commands = completion.spec(parser)
    assert {c.name for c in commands} == set(cli.COMMANDS)
    for c in commands:
        assert c.name in script
        for o in c.options:
            for flag in o.flags:
                bare = flag.lstrip("-")
                assert (flag in script) or (shell == "fish" and bare in script), (c.name, flag)
    binary = shutil.which(shell)
    if binary is not None and shell != "bash":
        check = [binary, "-n"] if shell == "zsh" else [binary, "--no-execute"]
        assert subprocess.run(check, input=script, text=True).returncode == 0


def test_completion_needs_a_known_shell(capsys) -> None:
    assert cli.main(["completion", "tcsh"]) == 2
    assert "invalid choice" in capsys.readouterr().err
