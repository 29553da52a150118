"""The ``bayesupdate`` parser of a run adds the arguments of the command it runs only: a run does
not enter every other command's module (``studies/room_walks.py``), and ``--help`` still lists
every command."""

import pytest

from bayesupdate import cli


def test_a_run_adds_only_its_commands_arguments(monkeypatch, capsys):
    added = []
    for module in cli._command_modules():
        original = module.add_arguments

        def counted(parser, _name=module.NAME, _original=original):
            added.append(_name)
            _original(parser)

        monkeypatch.setattr(module, "add_arguments", counted)
    assert cli.main(["modes", "--json", "--quiet"]) == 0
    assert added == ["modes"]
    assert '"frequencies_hz"' in capsys.readouterr().out


def test_help_lists_every_command_and_a_typo_is_one_line(capsys):
    names = [m.NAME for m in cli._command_modules()]
    assert len(names) == 11
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    out = capsys.readouterr().out
    assert all(name in out for name in names)
    assert cli.main(["modez", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "invalid choice: 'modez'" in err


def test_the_command_is_the_first_word_that_is_not_an_option():
    assert cli._command_in(["--quiet", "sample", "study.toml", "--steps", "10"]) == "sample"
    assert cli._command_in(["--version"]) is None
    assert cli._command_in([]) is None


def test_a_reader_that_leaves_the_pipe_is_no_internal_error():
    """``bayesupdate modes --json | head -c 1``: the reader closes the pipe before the command
    writes; the command ends with exit code 1 and says nothing, where it printed 'internal
    error: BrokenPipeError'.  (The read end is closed before the child has imported the
    package, so its first write meets the closed pipe.)"""
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-m", "bayesupdate", "modes", "--json", "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    child.stdout.close()
    err = child.stderr.read().decode()
    assert child.wait(timeout=120) == 1
    assert "internal error" not in err and "Traceback" not in err, err
