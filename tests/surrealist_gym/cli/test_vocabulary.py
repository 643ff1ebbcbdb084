"""One command-line vocabulary: ``--random-seed`` is the noise seed everywhere and ``--seed`` a seed test; one
``--out`` pattern; defaults that differ by problem stated once; an option that does not apply refused before any
work; ``train`` (PPO or SAC, alias ``train-ppo``); ``compare --case-study``."""
import argparse
import inspect
import json
import re
import warnings

import pytest

import surrealist_gym as sg
from surrealist_gym.cli import _parser, main
from surrealist_gym.errors import SurrealistError
from tests.conftest import CASE_STUDIES

RQ2 = sg.data_path("rq2-seed.yaml")


def _help(command: str) -> str:
    """A sub-command's --help text on one line (unwrapped, its spaces collapsed)."""
    sub = next(a for a in _parser()._actions if a.dest == "command")
    parser = sub.choices[command]
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=100_000)
    return " ".join(parser.format_help().split())


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and "Traceback" not in err, err
    return err


class _Stop(SurrealistError):
    """Raised by a stand-in to end a command once it has shown what it would do."""


# --- --random-seed: the noise seed; --seed refused where it meant one ------------------------------------------------
@pytest.mark.parametrize("argv", [
    ["simulate", RQ2], ["fidelity", "tests.csv"], ["compete", "tool", "mission1", "5"], ["export-tool", "{tmp}/tool"]],
    ids=lambda argv: argv[0])
def test_seed_that_meant_the_noise_seed_is_refused_in_one_line(tmp_path, capsys, argv):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main([*argv, "--seed", "3", "--out", str(tmp_path / "out")]) == 2
    err = _one_line_error(capsys)
    assert "--seed: use --random-seed" in err
    assert not (tmp_path / "out").exists() and not (tmp_path / "tool").exists()


def test_simulate_flies_with_the_random_seed(tmp_path, monkeypatch, capsys):
    import surrealist_gym.sim as sim

    seeds = []

    def fake(test, runs, seed, config):
        seeds.append(seed)
        raise _Stop("stop")

    monkeypatch.setattr(sim, "simulate", fake)
    assert main(["simulate", RQ2, "--random-seed", "7", "--out", str(tmp_path / "sim")]) == 2
    assert seeds == [7]


def test_fidelity_flies_with_the_random_seed(tmp_path, monkeypatch, capsys):
    import surrealist_gym.fidelity.measure as measure

    seeds = []
    monkeypatch.setattr(measure, "load_labelled_set", lambda *a: object())

    def fake(lset, runs, seed, **kw):
        seeds.append(seed)
        raise _Stop("stop")

    monkeypatch.setattr(measure, "measure_fidelity", fake)
    assert main(["fidelity", str(tmp_path / "tests.csv"), "--random-seed", "5", "--out", str(tmp_path / "f")]) == 2
    assert seeds == [5]


def test_compete_and_export_tool_take_the_random_seed(tmp_path, monkeypatch, capsys):
    import surrealist_gym.competition.compete as compete
    import surrealist_gym.competition.export_tool as export_tool

    seen = {}

    def fake_prepare(tool, case_study, budget, out, **kw):
        seen["compete"], seen["out"] = kw["seed"], out
        raise _Stop("stop")

    def fake_write(folder, settings):
        seen["export-tool"] = settings.seed
        raise _Stop("stop")

    monkeypatch.setattr(compete, "prepare", fake_prepare)
    monkeypatch.setattr(export_tool, "write_tool", fake_write)
    assert main(["compete", "tool", "mission1", "5", "--random-seed", "4"]) == 2
    assert main(["export-tool", str(tmp_path / "tool"), "--random-seed", "6"]) == 2
    assert seen["compete"] == 4 and seen["export-tool"] == 6
    assert re.fullmatch(r"results/compete-\d{8}-\d{6}", seen["out"].as_posix())  # compete's --out default
    assert main(["export-tool", str(tmp_path / "tool"), "--random-seed", "-1"]) == 2
    assert "--random-seed: expected a whole number >= 0, got -1" in capsys.readouterr().err


def test_seed_still_names_a_seed_test_where_it_did(capsys):
    for command in ("replicate", "compare", "train", "calibrate"):
        assert "TEST.yaml" in _help(command).split("--seed", 1)[1][:40], command


# --- one --out pattern ------------------------------------------------------------------------------------------------
def test_every_command_that_writes_a_folder_defaults_to_one_pattern():
    from surrealist_gym.cli.options import default_out

    assert re.fullmatch(r"results/simulate-\d{8}-\d{6}", default_out("simulate").as_posix())
    for command in ("simulate", "replicate", "generate", "compare", "fidelity", "evaluate", "compete"):
        assert "--out DIR" in _help(command), command
        assert f"(default results/{command}-YYYYmmdd-HHMMSS)" in _help(command), command
    assert "(default results/train-YYYYmmdd-HHMMSS/policy.zip)" in _help("train")
    for old in ("sim_out", "fidelity_out", "<time>", "<timestamp>"):
        assert not any(old in _help(c) for c in ("simulate", "fidelity", "compare", "evaluate", "compete",
                                                 "replicate", "generate")), old


def test_simulate_without_out_writes_results_simulate_time(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", RQ2, "--runs", "1", "--no-plot", "--no-ulog", "--json"]) == 0
    folders = [p.relative_to(tmp_path).as_posix() for p in (tmp_path / "results").iterdir()]
    assert len(folders) == 1 and re.fullmatch(r"results/simulate-\d{8}-\d{6}", folders[0])


# --- defaults stated once per problem ---------------------------------------------------------------------------------
def test_problem_defaults_are_the_envs_and_each_help_states_its_own():
    from surrealist_gym.cli.generate import CASE_STUDY_DEFAULTS
    from surrealist_gym.cli.options import PROBLEM_DEFAULTS, GenerateOptions, ReplicateOptions
    from surrealist_gym.competition.case_study_env import CaseStudyEnv
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.envs.replicate import ReplicateEnv

    assert CASE_STUDY_DEFAULTS is PROBLEM_DEFAULTS["case study"]
    for problem, env in (("replicate", ReplicateEnv), ("generate", GenerateEnv), ("case study", CaseStudyEnv)):
        params = inspect.signature(env.__init__).parameters
        for name in ("budget", "runs"):
            assert params[name].default == PROBLEM_DEFAULTS[problem][name], (problem, name)
    for name in ("budget", "runs", "agent"):
        assert getattr(ReplicateOptions(), name) == PROBLEM_DEFAULTS["replicate"][name]
        assert getattr(GenerateOptions(), name) == PROBLEM_DEFAULTS["generate"][name]
    gen, rep = _help("generate"), _help("replicate")
    assert "--runs RUNS simulations per evaluation (default 10; with --case-study 1)" in gen
    assert "--budget BUDGET evaluations allowed (default 50; with --case-study 200)" in gen
    assert "(default greedy; with --case-study suite)" in gen
    assert "then the defaults are --budget 200 --runs 1 --agent suite" in gen
    assert "--runs RUNS simulations per evaluation (default 5)" in rep
    assert "the log's vehicle" in rep and "the log's vehicle" not in gen  # each says only its own UAV default
    assert "seed test with a reference log" in gen and "seed test with a reference log" not in rep
    assert "case-study" not in rep and "generate" not in rep.split("options:", 1)[1]
    assert ("default: the env's: Surrealist-Replicate-v0 5, Surrealist-Generate-v0 10, Surrealist-CaseStudy-v1 1"
            in _help("compare"))
    assert "(default 5; with --competition the edition's: 2024 5, 2025 3, 2026 3)" in _help("evaluate")


# --- an option that does not apply is refused, before any work --------------------------------------------------------
@pytest.mark.parametrize("argv, message", [
    (["generate", "--obstacles", "2", "--confirm", "3"], "--obstacles: applies only with --case-study"),
    (["generate", "--confirm", "3"], "--confirm: applies only with --case-study"),
    (["generate", "--obst", "2"], "--obstacles: applies only with --case-study"),  # an abbreviation too
    (["generate", "--case-study", "mission1", "--all-mutators"], "--all-mutators: not with --case-study"),
    (["generate", "--agent", "random", "--preset", "paper"], "--preset: applies only to --agent greedy"),
    (["generate", "--case-study", "mission1", "--preset", "paper"], "--preset: applies only to --agent greedy"),
    (["generate", "--wind", "--surrogate", "online"], "--wind: not with pre-screening"),
    (["replicate", "--agent", "cmaes", "--preset", "authors"], "--preset: applies only to --agent greedy"),
    (["simulate", RQ2, "--reference", "x.ulg", "--no-reference"], "--no-reference: not allowed with"),
    (["compare", "--env", "Surrealist-Generate-v0", "--case-study", "mission1"],
     "--case-study: applies only to Surrealist-CaseStudy-v1"),
    (["compare", "--case-study", "mission1", "--seed", RQ2], "--seed: not with a case study"),
    (["compare", "--env", "Surrealist-Generate-v0", "--log", "x.ulg"],
     "--log: applies only to Surrealist-Replicate-v0"),
    (["compare", "--inline", "--workers", "2"], "--workers: not with --inline"),
    (["compare", "--inline", "--parallel", "2"], "--parallel: not with --inline"),
    (["compare", "--inline", "--dask-scheduler", "tcp://127.0.0.1:1"], "--dask-scheduler: not with --inline"),
    (["compare", "--dask-scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "--workers: not with --dask-scheduler"),
    (["fidelity", "{tmp}", "--mission", RQ2], "--mission: applies only to a tests CSV"),
    (["surrogate", "train", "{store}", "--kind", "ensemble", "--k", "3"], "--k: applies only to --kind knn"),
    (["surrogate", "train", "{store}", "--kind", "knn", "--members", "3"], "--members: applies only to --kind"),
    (["surrogate", "train", "{store}", "--problem", "generate", "--log", "x.ulg"],
     "--log: applies only to --problem replicate"),
    (["train", "--problem", "generate", "--case-study", "mission2"],
     "--case-study: applies only to --problem case-study"),
    (["train", "--obstacles", "2"], "--obstacles: applies only to --problem case-study"),
    (["train", "--problem", "case-study", "--case-study", "mission2", "--spread", "0.5"],
     "--spread: not with --problem case-study"),
    (["train", "--problem", "case-study", "--case-study", "mission2", "--seed", RQ2],
     "--seed: not with --problem case-study"),
    (["train", "--problem", "case-study"], "--problem case-study: name the case study with --case-study"),
    (["train", "--problem", "case-study", "--case-study", "mission2", "--obstacles", "4"],
     "--obstacles: the competition allows 1 to 3 boxes, got 4"),
], ids=lambda v: " ".join(map(str, v)) if isinstance(v, list) else None)
def test_an_option_that_does_not_apply_is_refused_in_one_line(tmp_path, capsys, argv, message):
    store = tmp_path / "s.sqlite"
    store.write_bytes(b"not empty")
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{store}", str(store)) for a in argv]
    out = tmp_path / "out"
    assert main([*argv, "--out", str(out)]) == 2
    assert message in _one_line_error(capsys)
    assert not out.exists()


def test_an_option_that_applies_is_not_refused():
    from surrealist_gym.cli.options import GenerateOptions, refuse_inapplicable

    def check(flags, **values):
        args = argparse.Namespace(_flags=frozenset(flags), **{"agent": "greedy", "case_study": None, **values})
        refuse_inapplicable(args, GenerateOptions.inapplicable(args))

    check({"--preset", "--agent", "--obstacles", "--confirm"}, case_study="mission1")  # greedy typed: its preset
    check({"--preset", "--all-mutators"})
    with pytest.raises(SurrealistError, match="--preset: applies only to --agent greedy"):  # suite by default
        check({"--preset"}, case_study="mission1")


# --- train: PPO or SAC; train-ppo still works -------------------------------------------------------------------------
def test_train_ppo_is_an_alias_of_train(tmp_path, capsys):
    for command in ("train", "train-ppo"):
        assert main([command, "--steps", "0", "--out", str(tmp_path / "p.zip")]) == 2
        assert "--steps: expected a whole number >= 1, got 0" in _one_line_error(capsys)
    assert "--algorithm {ppo,sac}" in _help("train") and _help("train") == _help("train-ppo")


def test_train_with_sac_runs_a_few_steps_and_its_policy_searches(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    from search.registry import make_agent

    out = tmp_path / "sac.zip"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["train", "--algorithm", "sac", "--problem", "generate", "--steps", "4", "--episode-budget", "2",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert out.is_file() and "trained sac for 4 steps on generate problems" in printed
    assert f"sac:{out}" in printed
    make_agent(f"sac:{out}", seed=0)  # a SAC policy, loadable as an agent


def test_train_on_a_case_study_runs_a_few_steps_and_writes_its_results_folder(tmp_path, capsys, monkeypatch):
    """``train --problem case-study``: PPO on Surrealist-CaseStudy-v1 for 8 steps; the folder holds the policy and
    its record (policy.json), and the policy searches the case study as an agent."""
    pytest.importorskip("stable_baselines3")
    import gymnasium as gym

    from search.registry import make_agent

    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["train", "--problem", "case-study", "--case-study", str(CASE_STUDIES / "mission2.yaml"),
                     "--obstacles", "1", "--steps", "8", "--episode-budget", "3"]) == 0
    printed = capsys.readouterr().out
    folders = list((tmp_path / "results").iterdir())
    assert len(folders) == 1 and re.fullmatch(r"train-\d{8}-\d{6}", folders[0].name)  # as the other problems
    policy, record = folders[0] / "policy.zip", json.loads((folders[0] / "policy.json").read_text())
    assert policy.is_file() and "trained ppo for 8 steps on case study mission2" in printed
    assert record["problem"] == "case-study" and record["obstacles"] == 1 and record["record"]["steps"] == 8
    assert record["record"]["flown"] + record["record"]["refused"] + record["record"]["memo"] == 8
    env = gym.make("Surrealist-CaseStudy-v1", case_study=CASE_STUDIES / "mission2.yaml", obstacles=1, budget=2,
                   executor="inline")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = make_agent(f"ppo:{policy}", seed=0).run(env)
    assert result.evaluations == 2 and result.best_action.shape == (6,)
    env.close()


# --- compare --case-study ---------------------------------------------------------------------------------------------
def test_compare_runs_on_a_case_study(tmp_path, capsys):
    out = tmp_path / "cmp"
    case_study = CASE_STUDIES / "mission1.yaml"
    assert main(["compare", "--case-study", str(case_study), "--agents", "random", "--repetitions", "1",
                 "--budget", "1", "--runs", "1", "--inline", "--out", str(out)]) == 0
    settings = json.loads((out / "compare.json").read_text())
    assert settings["env_id"] == "Surrealist-CaseStudy-v1"
    assert settings["env_kwargs"] == {"case_study": str(case_study.resolve()), "uav": "px4-v1.12-sitl-iris"}
    assert "| random | 1 |" in capsys.readouterr().out


def test_compare_refuses_a_case_study_that_does_not_exist(tmp_path, capsys):
    assert main(["compare", "--case-study", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "cmp")]) == 2
    assert "no such file" in _one_line_error(capsys) and not (tmp_path / "cmp").exists()
