"""Progress of long phases (``compute.progress``): silent in the library, one line per phase or
a bar at the CLI, nothing with --quiet, wall times recorded in every mode."""

import io

from bayesupdate.cli import main
from bayesupdate.compute import progress
from bayesupdate.compute.progress import mode_for, phase, reporting
from bayesupdate.fe.reduced import reduced_model_for
from bayesupdate.models import get_model


def _show_every_phase(monkeypatch):
    """Show phases of any length (the tests' phases take microseconds)."""
    monkeypatch.setattr(progress, "SHOWN_FROM_S", 0.0)


def test_phases_are_silent_outside_a_reporting_context(capsys):
    with phase("work", 3) as p:
        for _ in range(3):
            p.advance()
    assert p.count == 3
    assert capsys.readouterr() == ("", "")


def test_lines_mode_prints_one_line_per_phase_with_its_count_and_records_it(monkeypatch):
    _show_every_phase(monkeypatch)
    stream = io.StringIO()
    with reporting("lines", stream) as rec:
        with phase("first", 2, "solves") as p:
            p.advance(2)
        with phase("second") as p:
            pass
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("first: 2 solves in ") and lines[1].startswith("second: done in ")
    assert [(t.name, t.count) for t in rec.phases] == [("first", 2), ("second", 0)]
    assert set(rec.timings()) == {"first", "second"}


def test_off_mode_shows_nothing_but_still_times_the_phases():
    stream = io.StringIO()
    with reporting("off", stream) as rec:
        with phase("quiet work", 1) as p:
            p.advance()
    assert stream.getvalue() == ""
    assert rec.phases[0].count == 1 and rec.phases[0].wall_s >= 0


def test_mode_for_a_terminal_a_pipe_and_quiet():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    assert mode_for(False, Tty()) == "bar"
    assert mode_for(False, io.StringIO()) == "lines"
    assert mode_for(True, Tty()) == "off"


def test_a_short_phase_is_timed_but_not_shown():
    stream = io.StringIO()
    with reporting("lines", stream) as rec:
        with phase("quick", 1) as p:
            p.advance()
    assert stream.getvalue() == "" and rec.phases[0].count == 1


def test_a_reduced_basis_build_reports_its_solves(monkeypatch):
    _show_every_phase(monkeypatch)
    stream = io.StringIO()
    with reporting("lines", stream) as rec:
        rom = reduced_model_for(get_model("exhaust"), None, n_modes=6, n_snapshots=8,
                                n_validation=8)  # fmt: skip
    names = [t.name for t in rec.phases]
    assert names[0] == "reduced basis: snapshots" and rec.phases[0].count == 8
    rounds = [t for t in rec.phases if t.name.startswith("reduced basis: certification")]
    assert len(rounds) == len(rom.certification.history)
    assert all(t.count == 8 for t in rounds)
    assert stream.getvalue().count("\n") == len(rec.phases)


def test_the_cli_reports_on_stderr_and_quiet_silences_it(monkeypatch, capsys):
    _show_every_phase(monkeypatch)

    def fake_run(args):
        with phase("a phase", 1) as p:
            p.advance()
        print('{"ok": 1}')
        return 0

    monkeypatch.setattr("bayesupdate.commands.modes.run", fake_run)
    assert main(["modes"]) == 0
    out, err = capsys.readouterr()
    assert out == '{"ok": 1}\n' and err.startswith("a phase: 1 it in ")
    assert main(["modes", "--quiet"]) == 0
    assert capsys.readouterr() == ('{"ok": 1}\n', "")
