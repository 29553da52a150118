"""The walks of a ``discover`` and a ``sample`` run through the package's rooms
(``studies/room_walks.py``, the path reading): no call's stack enters a room more than twice
or climbs to a higher layer more than twice, and every climb is a callback (a function handed
down, as to an executor), never a lower room naming a higher one. Before the compute room and
discovery's one task entry (6a78c33), a discover run's stack entered ``discovery`` three times
(discovery > parallel_executor > discovery > inference > discovery)."""

import importlib.util
import re
from collections import Counter
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "studies" / "room_walks.py"
_SPEC = importlib.util.spec_from_file_location("room_walks", _PATH)
walks = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(walks)


def _shorter(text: str, **keys) -> str:
    """The study file ``text`` with the lines of ``keys`` set to their values (a shorter run
    of the study's own walk: the same commands, rooms and paths)."""
    for key, value in keys.items():
        text, found = re.subn(rf"^{key} = .*$", f"{key} = {value}", text, flags=re.M)
        assert found == 1, key
    return text


DISCOVER = _shorter(walks.DISCOVERY_STUDY, quick_refits=1, max_nfev=2, loo_top=0, loo_draws=25)
SAMPLE = _shorter(walks.SAMPLE_STUDY, steps=20, check_every=10, predictive_draws=10)


def test_the_path_reading_counts_entries_and_climbs_on_one_stack():
    tracer = walks.WalkTracer()
    legacy = ("cli", "commands", "pipelines", "discovery", "compute", "discovery", "inference")
    tracer.paths = Counter({(*legacy, "discovery"): 3, ("cli", "commands", "pipelines"): 1})
    entries, (up, path) = walks.path_walk(tracer)
    assert entries["discovery"][0] == 3
    assert entries["pipelines"][0] == 1
    # compute -> discovery and inference -> discovery go up a layer; the rest go down
    assert up == 2
    assert path[-1] == "discovery"


@pytest.mark.parametrize("command, study", [("discover", DISCOVER), ("sample", SAMPLE)])
def test_a_run_enters_each_room_at_most_twice_on_a_path(command, study, tmp_path):
    (tmp_path / "study.toml").write_text(study)
    tracer = walks.traced([command, str(tmp_path / "study.toml"), "--json", "--quiet"])
    entries, (up, path) = walks.path_walk(tracer)
    assert len(tracer.paths) > 20  # the tracer saw the run, not only the command's parser
    assert {"pipelines", "inference", "fe", "compute"} <= set(entries)
    assert max(times for times, _ in entries.values()) <= 2, entries
    assert up <= 2, path
    named = [site for key, found in tracer.sites.items() if walks.climbs(key) for site in found]
    assert set(named) <= tracer.callbacks, set(named) - tracer.callbacks
