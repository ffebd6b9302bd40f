"""Short fuzz run (issue 8, §1): hostile input ends in a result or a MechcircError.

The generators and the property live in ``tests/fuzz/harness.py``; the long
run (≥ 100,000 inputs) is ``tests/fuzz/long_run.py`` and its numbers are in
``docs/reliability.md``.  By default each property runs a small share
(:data:`BUDGET`) of its full count, so the suite stays quick;
``MECHCIRC_FUZZ_BUDGET=1 python -m pytest tests/fuzz`` runs the full counts
(18,680 inputs).  Two kinds of input here, derandomised so that a failure
reproduces:

* hypothesis text strategies over the grammars' alphabets (shrunk to a
  minimal failing text by hypothesis);
* the harness's generators (grammar-built netlists, mutations of the bundled
  netlists and linkage files, random command lines), driven by a seed that
  hypothesis draws — the failing seed is printed and reproduces the input.
"""

from __future__ import annotations

import os
import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fuzz import harness as h


def _budget() -> float:
    text = os.environ.get("MECHCIRC_FUZZ_BUDGET", "0.05")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value <= 100:
        raise pytest.UsageError(f"MECHCIRC_FUZZ_BUDGET must be a number in (0, 100], the share "
                                f"of the full fuzz counts to run; got {text!r}")
    return value


#: Share of each property's full count run (environment variable MECHCIRC_FUZZ_BUDGET;
#: default 0.05, i.e. 950 of the 18,680 inputs; 1 runs them all).
BUDGET = _budget()


def fast(n: int):
    """Settings for a property whose full count is ``n`` inputs: ``BUDGET × n`` of them, at least 5."""
    return settings(max_examples=max(5, round(n * BUDGET)), deadline=None, derandomize=True,
                    database=None, suppress_health_check=list(HealthCheck))


seeds = st.integers(0, 2**32 - 1)

EXPRESSION_ALPHABET = "0123456789.eE+-*/^() \t{}pixysqrtlogexp_,=#é\u2212"
NETLIST_WORDS = st.sampled_from(
    ["mass", "spring", "damper", "lever", "drive", ".param", "a", "b", "0", "m", "k",
     "velocity=1", "force=2", "ratio=0.5", "eta=2", "1", "2.5", "1e308", "1e-320", "{1/0}",
     "{-1}", "p=3", "p", "kg", "N/mm", "#", ";", "{", "}", "=", "9**9**9", "\u2212"])


@fast(3000)
@given(st.text(alphabet=EXPRESSION_ALPHABET, max_size=60))
def test_fuzz_expression_text(text):
    h.expression_property(text)


@fast(5000)
@given(seeds)
def test_fuzz_expressions(seed):
    h.expression_property(h.expression_input(random.Random(seed)))


@fast(1500)
@given(st.lists(st.lists(NETLIST_WORDS, max_size=8).map(" ".join), max_size=8)
       .map("\n".join))
def test_fuzz_netlist_words(text):
    h.netlist_property(text)


@fast(5000)
@given(seeds)
def test_fuzz_netlists(seed):
    h.netlist_property(h.netlist_input(random.Random(seed)))


@fast(3000)
@given(seeds)
def test_fuzz_linkage_files(seed):
    h.linkage_property(h.toml_input(random.Random(seed)))


@fast(100)
@given(seeds)
def test_fuzz_public_analyses_of_valid_networks(seed):
    """(Found: ``Circuit.unloaded`` raised NotSeriesParallelError for a mesh with a lever.)"""
    h.api_property(h.api_network(seed))


@pytest.fixture(scope="module")
def cli_workdir(tmp_path_factory):
    work = tmp_path_factory.mktemp("cli_fuzz")
    return work, h.cli_files(work, random.Random(8))


@fast(60)
@given(seed=seeds)
def test_fuzz_cli_arguments(cli_workdir, seed):
    work, files = cli_workdir
    h.cli_property(h.cli_argv(random.Random(seed), work, files))


# ------------------------------------------------------------- the harness itself
def test_harness_reports_foreign_exceptions():
    """The property fails on a non-mechcirc exception and on a hang (it could fail)."""
    with pytest.raises(h.PropertyFailure, match="ZeroDivisionError"):
        h.run_target(lambda: 1 / 0, None)
    with pytest.raises(h.PropertyFailure, match="hang"):
        h.run_target(lambda: [None for _ in iter(int, 1)], None, seconds=0.2)


def test_harness_checks_error_locations():
    from mechcirc.errors import NetlistError

    def bad():
        raise NetlistError("x", "<string>", 3, 1)

    with pytest.raises(h.PropertyFailure, match="outside the text"):
        h.run_target(bad, "one line\n")
    assert h.run_target(bad, "a\nb\nc\n") == "error"


def _reach(outcome, seeds, enough):
    """Outcomes of ``outcome(seed)`` over ``seeds``, counted until each reaches ``enough``.

    The counts only grow with more seeds, so stopping once every count is past
    its threshold decides "over these seeds, at least that many" as running
    them all would, without the rest of the runs.
    """
    seen = dict.fromkeys(enough, 0)
    for i in seeds:
        seen[outcome(i)] += 1
        if all(seen[k] >= n for k, n in enough.items()):
            break
    return seen


def test_generators_reach_results_and_errors():
    """The generators are not stuck in one corner: both outcomes occur often
    (over seeds 0-299 of netlists, > 15 results and > 30 errors; over seeds 0-199
    of linkage files, > 3 results and > 100 errors)."""
    seen = _reach(lambda i: h.netlist_property(h.netlist_input(random.Random(i))),
                  range(300), {"result": 16, "error": 31})
    assert seen["result"] > 15 and seen["error"] > 30, seen
    toml = _reach(lambda i: h.linkage_property(h.toml_input(random.Random(i))),
                  range(200), {"result": 4, "error": 101})
    assert toml["result"] > 3 and toml["error"] > 100, toml


# ------------------------------------------------------------------ issue 16: files of every kind
@pytest.fixture(scope="module")
def file_workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("files")


@pytest.mark.parametrize("kind", h.FILE_KINDS)
@fast(60)
@given(seeds)
def test_fuzz_files_of_every_kind(file_workdir, kind, seed):
    """Hostile values, lists where names belong, huge integers, non-UTF-8, pickles,
    binary files and line-break characters: a result or a located MechcircError."""
    h.file_property(kind, h.file_input(random.Random(seed), kind), file_workdir)


def test_file_generators_reach_each_hazard():
    rng = random.Random(5)
    blobs = [h.file_input(rng, k) for k in h.FILE_KINDS for _ in range(200)]
    assert any(b.startswith(b"\x80") for b in blobs)                       # pickles
    assert any(b"\xff" in b or b"\xc3" in b for b in blobs)                # not UTF-8
    assert any(ch.encode() in b for b in blobs for ch in ("\x0c", "\u2028"))
    assert any(b"9" * 300 in b for b in blobs)                             # huge integers
    assert any(b'= ["' in b or b"= [-12]" in b for b in blobs)             # lists for names


def test_a_pickle_given_as_a_data_file_is_never_loaded(file_workdir):
    import pickle

    data = pickle.dumps({"K": [1, 2]})
    for kind in h.FILE_KINDS:
        assert h.file_property(kind, data, file_workdir) == "error"


@pytest.mark.slow
@pytest.mark.parametrize("n", [4000])
def test_parallel_and_series_blowups_finish_in_bounded_time(n):
    for seed in range(2):
        h.netlist_blowup_property(h.blowup_netlist(random.Random(seed), n))


@pytest.mark.parametrize("seed", [1012357, 1025632, 1025932, 1059107])
def test_long_run_seeds_of_huge_integers_in_scene_files(file_workdir, seed):
    """The 100,000-file long run: integers beyond float64 in a scene's load direction
    and [simulate] numbers were an OverflowError; now located user errors."""
    kind = h.FILE_KINDS[seed % len(h.FILE_KINDS)]
    h.file_property(kind, h.file_input(random.Random(seed), kind), file_workdir)


# ------------------------------------------------------------------ issue 23: this round's inputs
@pytest.fixture(scope="module")
def round_workdir(tmp_path_factory):
    work = tmp_path_factory.mktemp("round")
    return work, h.round_files(work)


@pytest.mark.parametrize("kind", [k for k in h.ROUND_KINDS if k != "crosscheck"])
@fast(100)
@given(seed=seeds)
def test_fuzz_this_rounds_commands(round_workdir, kind, seed):
    """periodic (motion laws and tables), cam, resonances --modes --sensitivity, sweep
    --sensitivity/--node/--element/--unit and study sample files: exit 0 or 2, never 1,
    a traceback or a hang."""
    work, files = round_workdir
    h.cli_property(h.round_argv(random.Random(seed), kind, work, files))


@fast(20)
@given(seed=seeds)
def test_fuzz_crosscheck_verdicts(round_workdir, seed):
    """crosscheck runs transients (about a second each): fewer inputs; exit 3 is a verdict."""
    work, files = round_workdir
    h.cli_property(h.round_argv(random.Random(seed), "crosscheck", work, files))


def test_round_generators_reach_results_and_errors(tmp_path):
    """Each kind of this round's inputs ends both ways (not stuck in the argument parser):
    on seeds 0-11 every kind has at least one result and at least two user errors."""
    files = h.round_files(tmp_path)
    for kind in h.ROUND_KINDS:
        if kind == "crosscheck":
            continue                    # seconds per input; covered by the property above
        seen = _reach(lambda i, kind=kind: h.cli_property(h.round_argv(random.Random(i), kind,
                                                                       tmp_path, files)),
                      range(12), {"result": 1, "error": 2})
        assert seen["result"] >= 1 and seen["error"] >= 2, (kind, seen)


# ------------------------------------------------------------------ the campaign: every command
@pytest.fixture(scope="module")
def all_workdir(tmp_path_factory):
    work = tmp_path_factory.mktemp("all")
    return work, h.all_files(work)


@fast(100)
@given(seed=seeds)
def test_fuzz_every_command(all_workdir, seed):
    """Any registered sub-command, from its --help example made wrong or from its options
    at random, on the file kind it reads: exit 0, 2 (3: a crosscheck verdict), never 1."""
    work, pools = all_workdir
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(work)                   # a relative output name lands in the work folder
        h.cli_property(h.all_argv(random.Random(seed), work, pools))


def test_campaign_generator_reaches_every_command(tmp_path):
    """all_argv draws every registered sub-command, and study specs of every sampling
    method (generation only: nothing is run)."""
    pools = h.all_files(tmp_path)
    seen, methods = set(), set()
    for i in range(300):
        argv = h.all_argv(random.Random(i), tmp_path, pools)
        seen.add(argv[0])
        if argv[0] == "study":
            spec = (tmp_path / "study" / "spec.toml").read_text()
            methods |= {m for m in ("[grid]", "latin-hypercube", "sobol", "[random]",
                                    'file = "designs.csv"') if m in spec}
    assert seen >= set(h.cli_commands())
    assert len(methods) == 5, methods
