"""One spelling in the package, its tests, studies, benchmarks and docs: -ize (Oxford spelling, as
numpy and scipy write ``vectorize`` and ``optimize``), so that a name is found by one search and
a user never meets two spellings of one word.  The -ise forms left are on lines that name both
spellings, records of a rename, such as these:
``inference.summarise`` (deprecated: a warning, then ``inference.summarize``),
``mass_normalised`` in older modes files (read as ``mass_normalized``),
and the CHANGELOG's entries."""

import re
import subprocess
import warnings
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: the word stems that take -ize / -isation in English (checked: every match in the tree)
STEMS = ("normal|vector|factor|summar|linear|recogn|real|optim|stabil|local|maxim|minim|standard|"
         "random|parametr|oval|serial|memo|initial|general|discret|synthes")  # fmt: skip
ISE = re.compile(r"(?i)(" + STEMS + r")(is)(e|ed|es|ing|ation|ations|er|ers|able)(?![a-z])")


def _recorded_rename(match: re.Match, line: str) -> bool:
    """A line that names both spellings of a word records its rename (the compatibility maps,
    the CHANGELOG's entry): allowed."""
    word = match.group(0)
    return (
        word[: match.start(2) - match.start(0)] + "iz" + word[match.end(2) - match.start(0) :]
        in line
    )


def _tracked_text() -> list[Path]:
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True).stdout
    if not out:  # not a git checkout (an sdist): the package and docs as found
        return [p for p in ROOT.rglob("*") if p.suffix in (".py", ".md", ".toml")
                and ".venv" not in p.parts]  # fmt: skip
    return [ROOT / f for f in out.split() if f.endswith((".py", ".md", ".toml", ".yml"))]


def test_every_word_of_these_stems_is_spelt_with_ize():
    found = []
    for path in _tracked_text():
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for m in ISE.finditer(line):
                if not _recorded_rename(m, line):
                    found.append(f"{path.relative_to(ROOT)}:{k}: {m.group(0)}")
    assert not found, "\n".join(found[:20])


def test_the_old_summarise_warns_and_is_summarize():
    import bayesupdate.inference as inference

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old, new = inference.summarise, inference.summarize
    assert old is new
    assert any(issubclass(w.category, DeprecationWarning) and "summarize" in str(w.message)
               for w in caught)  # fmt: skip


def test_an_older_modes_files_mass_normalised_key_reads_as_mass_normalized(tmp_path):
    from bayesupdate.ema.modal_h5 import read_modal_h5, write_modal_h5
    from bayesupdate.modal_data import ModalData

    path = tmp_path / "modes.h5"
    flags = np.array([True, False])
    write_modal_h5(path, ModalData(np.array([10.0, 20.0]), extra={"mass_normalized": flags}))
    with h5py.File(path, "r+") as fh:  # as release 0.1 wrote it
        fh["modes/extra"].move("mass_normalized", "mass_normalised")
    extra = read_modal_h5(path).extra
    np.testing.assert_array_equal(extra["mass_normalized"], flags)
    assert "mass_normalised" not in extra and "mass_normalized" in extra
