"""Shared fixtures of the tools' tests, and the one-line-per-test report of run_pytest.sh."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
MONTECARLO = REPO / "tools" / "montecarlo.sh"
AGGLO_STATS = REPO / "tools" / "agglo-stats"
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(Path(__file__).resolve().parent))


def pytest_runtest_logreport(report):
    """Append "PASS name" / "FAIL name: reason" to $AGGLO_PYTEST_REPORT (run_pytest.sh prints it)."""
    path = os.environ.get("AGGLO_PYTEST_REPORT")
    if not path:
        return
    name = report.nodeid.split("/")[-1].replace(".py::", ".")
    line = None
    if report.failed:
        crash = getattr(report.longrepr, "reprcrash", None)
        reason = crash.message if crash is not None else str(report.longrepr)
        reason = " ".join(reason.split())[:300]
        stage = "" if report.when == "call" else f"{report.when} error: "
        line = f"FAIL {name}: {stage}{reason}"
    elif report.skipped:
        # The suite has no optional tests: a skip is a test that did not run, so it fails.
        line = f"FAIL {name}: skipped ({report.longrepr[-1] if isinstance(report.longrepr, tuple) else ''})"
    elif report.when == "call":
        line = f"PASS {name}"
    if line:
        with open(path, "a") as handle:
            handle.write(line + "\n")


@pytest.fixture(scope="session")
def agglo():
    """The built executable (tests/run_tests.sh exports $AGGLO = path of build/agglo)."""
    path = os.environ.get("AGGLO", "")
    if not path or not os.access(path, os.X_OK):
        pytest.fail(f"$AGGLO = '{path}' is not an executable: run through tests/run_tests.sh after make build")
    return path


_PAIR_FLUID_NONE = re.compile(r"fluid\s*=\s*['\"]none['\"]", re.I)
_PAIR_PARTICLES = re.compile(r"particles\s*=\s*['\"]pair['\"]", re.I)


@pytest.fixture(scope="session")
def pair_deck():
    """A deck of input/ for the pair scene at fluid = 'none' (a needle deck when there is one).
    $AGGLO_PAIR_DECK names another deck explicitly."""
    explicit = os.environ.get("AGGLO_PAIR_DECK")
    if explicit:
        return str(Path(explicit).resolve())
    candidates = [p for p in sorted((REPO / "input").glob("*.nml"))
                  if _PAIR_FLUID_NONE.search(p.read_text()) and _PAIR_PARTICLES.search(p.read_text())]
    if not candidates:
        pytest.fail("no deck in input/ with &scene fluid = 'none' and particles = 'pair' "
                    "(the pair scene's decks have not landed)")
    needles = [p for p in candidates if "needle" in p.name]
    return str((needles or candidates)[0])


@pytest.fixture(scope="session")
def pair_scene(agglo, pair_deck, tmp_path_factory):
    """$AGGLO and the pair deck, once checked to complete one run of the pair scene (summary.json):
    the tests of real batches need the pair scene of the particle work."""
    directory = tmp_path_factory.mktemp("pair scene probe")
    deck = directory / "probe.nml"
    deck.write_text(Path(pair_deck).read_text() + "\n")
    result = run_tool([MONTECARLO, "--deck", deck, "--runs", "1", "--seed", "1", "--out",
                       directory / "batch", "--agglo", agglo, "--set", "run.end_time=1.0e-4"], cwd=REPO)
    if not (directory / "batch" / "run_0001" / "summary.json").exists():
        log = (directory / "batch" / "run_0001" / "stdout.log")
        tail = " | ".join(log.read_text().splitlines()[-3:]) if log.exists() else result.stderr
        pytest.fail(f"$AGGLO did not complete one pair-scene run of {pair_deck} (no summary.json; "
                    f"is the pair scene built?): {tail}")
    return agglo, pair_deck


@pytest.fixture
def spaced_tmp(tmp_path):
    """A temporary directory whose path contains spaces (the tools must cope with them)."""
    path = tmp_path / "dir with spaces"
    path.mkdir()
    return path


def run_tool(command, cwd=None, timeout=300):
    """Run a tool; returns CompletedProcess with text stdout/stderr."""
    return subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)
