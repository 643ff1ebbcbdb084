"""One command-line vocabulary (docs/cli.md), checked on the real parser of every sub-command: ``--seed TEST.yaml``
is a seed test and ``--random-seed N`` the noise seed everywhere; ``--runs N`` the times a test is flown; ``--out
DIR`` always a folder (a command writing one file names it: ``train --policy``, ``calibrate --profile``);
``--workers N`` and ``--dask-scheduler`` on every command that flies, the workers' default told as it is; old
spellings refused in one line before any work. Also: one ``--out`` pattern; defaults that differ by problem stated
once; an option that does not apply refused before any work; ``train`` (PPO or SAC, alias ``train-ppo``) and the
compare command it prints; ``compare --case-study`` and ``--obstacles``."""
import argparse
import inspect
import json
import re
import shlex
import warnings
from pathlib import Path

import pytest

import surrealist_gym as sg
from surrealist_gym.cli import _parser, main
from surrealist_gym.errors import SurrealistError
from tests.conftest import CASE_STUDIES

RQ2 = sg.data_path("rq2-seed.yaml")


def _commands() -> dict[str, argparse.ArgumentParser]:
    """Every sub-command's real parser by name (``surrogate train`` and ``surrogate eval`` by theirs; aliases
    left out)."""
    from surrealist_gym.cli import COMMANDS

    sub = next(a for a in _parser()._actions if a.dest == "command")
    parsers = {}
    for name in COMMANDS:
        parser = sub.choices[name]
        nested = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if nested:
            parsers.update({f"{name} {n}": p for n, p in nested[0].choices.items()})
        else:
            parsers[name] = parser
    return parsers


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    """The options a parser offers (those kept only to be refused left out), by flag."""
    from surrealist_gym.cli.options import Refused

    return {flag: a for a in parser._actions if not isinstance(a, Refused) for flag in a.option_strings}


def _positionals(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not a.option_strings and a.help is not argparse.SUPPRESS
            and not isinstance(a, argparse._SubParsersAction)]


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


# --- the vocabulary, rule by rule, on every sub-command's parser -----------------------------------------------------
def test_the_flying_commands_are_the_commands_that_fly():
    from surrealist_gym.cli.options import FLYING_COMMANDS

    parsers = _commands()
    assert set(FLYING_COMMANDS) <= set(parsers)
    for name, parser in parsers.items():  # a command that flies tests N times is one of them
        if "--runs" in _options(parser):
            assert name in FLYING_COMMANDS, f"{name} has --runs: add it to FLYING_COMMANDS (and docs/cli.md)"


def test_seed_is_a_seed_test_and_random_seed_the_noise_everywhere():
    from surrealist_gym.cli.options import FLYING_COMMANDS

    for name, parser in _commands().items():
        options = _options(parser)
        if "--seed" in options:
            assert options["--seed"].metavar.startswith("TEST.yaml"), name  # replicate: or tall, paper, detours
            assert "seed test" in options["--seed"].help or "test's obstacles" in options["--seed"].help, name
        for action in _positionals(parser):  # a seed test is never positional
            assert "seed test" not in (action.help or ""), (name, action.dest)
        if name in FLYING_COMMANDS or name in ("export-tool", "surrogate train"):
            seed = options.get("--random-seed")
            assert seed is not None and seed.type is int and seed.metavar == "N", name
            assert "seed" in seed.help and "default" in seed.help, name
    assert "--seed" not in _options(_commands()["generate"]) or \
        _options(_commands()["generate"])["--seed"].dest == "test"  # run.json's key stays


def test_runs_is_the_times_a_test_is_flown_everywhere():
    from surrealist_gym.cli.options import FLYING_COMMANDS

    for name, parser in _commands().items():
        options = _options(parser)
        assert not any(re.search(r"runs-per|--run$|repeats", flag) for flag in options), name
        if name in FLYING_COMMANDS:
            runs = options.get("--runs")
            assert runs is not None and runs.type is int and runs.metavar == "N", name


def test_out_is_always_a_folder_and_one_file_has_a_name_of_its_own():
    for name, parser in _commands().items():
        options = _options(parser)
        if "--out" in options:
            assert options["--out"].metavar == "DIR", name
            assert "folder" in options["--out"].help, name
    train, calibrate = _options(_commands()["train"]), _options(_commands()["calibrate"])
    assert "--out" not in train and train["--policy"].metavar == "FILE.zip"
    assert "--out" not in calibrate and calibrate["--profile"].metavar == "FILE.yaml"
    assert _options(_commands()["inspect"])["--out"].metavar == "DIR"
    predict = _options(_commands()["predict"])  # its table goes in --out DIR; the model is a file of its own
    assert predict["--out"].metavar == "DIR" and predict["--model"].metavar == "FILE.json"


def test_every_command_that_flies_takes_workers_and_a_dask_scheduler_and_tells_the_workers_default():
    from surrealist_gym.cli.options import FLYING_COMMANDS
    from surrealist_gym.executors import DEFAULT_MAX_WORKERS, LocalPoolExecutor, default_workers

    assert default_workers() == LocalPoolExecutor().workers <= DEFAULT_MAX_WORKERS
    for name, parser in _commands().items():
        options = _options(parser)
        if name not in FLYING_COMMANDS:
            continue
        workers, dask = options.get("--workers"), options.get("--dask-scheduler")
        assert workers is not None and dask is not None, name
        assert workers.type is int and workers.metavar == "N" and dask.metavar == "ADDRESS", name
        said = " ".join(workers.help.split())
        assert "default" in said, name
        if workers.default is None:  # the library's default: all cores, capped
            assert f"all cores, at most {DEFAULT_MAX_WORKERS}" in said, name
        else:
            assert f"default {workers.default}" in said, name


def test_obstacles_means_one_thing_where_it_is_taken():
    for name in ("generate", "compare", "train", "export-tool"):
        obstacles = _options(_commands()[name])["--obstacles"]
        assert obstacles.type is int and obstacles.metavar == "N" and re.search(r"1.(3|to 3)", obstacles.help), name


# --- old spellings: one line naming the new one, exit 2, before any work ----------------------------------------------
OLD_SPELLINGS = [
    (["generate", "{tmp}/seed.yaml", "--budget", "1"], "the seed test is given as --seed {tmp}/seed.yaml"),
    (["generate", "stray", "--budget", "1"], "stray: unexpected argument"),
    (["compete", "tool", "mission1", "5", "--runs-per-test", "2"], "--runs-per-test: use --runs"),
    (["compete", "tool", "mission1", "0"], "BUDGET: expected a whole number >= 1, got 0"),
    (["train", "--steps", "1", "--out", "{tmp}/p.zip"], "--out is a folder; the policy file is --policy {tmp}/p.zip"),
    (["train", "--steps", "1", "--out", "{tmp}/pol"], "--out is a folder; train writes one policy file: --policy "
                                                      "{tmp}/pol/policy.zip"),
    (["calibrate", "{tmp}/x.ulg", "--out", "{tmp}/u.yaml"], "--out is a folder; the profile file is --profile "
                                                            "{tmp}/u.yaml"),
    (["calibrate", "{tmp}/x.ulg", "--out", "{tmp}/cal"], "--profile {tmp}/cal/uav.yaml"),
    (["inspect", str(sg.data_path("case0.ulg")), "--out", "{tmp}/case0.png"],
     "--out is a folder; inspect writes <log name>.png in it: --out {tmp}"),
    (["simulate", RQ2, "--seed", "3"], "--seed: use --random-seed"),
    (["evaluate", RQ2, "--seed", "3"], "--seed: use --random-seed"),
]


@pytest.mark.parametrize("argv, message", OLD_SPELLINGS, ids=lambda v: " ".join(v[:2]) if isinstance(v, list) else None)
def test_an_old_spelling_is_refused_in_one_line_naming_the_new(tmp_path, capsys, argv, message):
    before = sorted(p.name for p in tmp_path.iterdir())
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    assert message.replace("{tmp}", str(tmp_path)) in _one_line_error(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_refused_spellings_are_not_offered_in_the_help():
    for command in ("generate", "compete", "train", "calibrate", "simulate"):
        text = _help(command)
        assert "--runs-per-test" not in text and "--out POLICY" not in text and "--out YAML" not in text, command
    assert "--seed TEST.yaml" in _help("generate") and "--policy FILE.zip" in _help("train")
    assert "--profile FILE.yaml" in _help("calibrate") and "--runs N" in _help("compete")


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
    for command in ("simulate", "replicate", "generate", "compare", "fidelity", "predict", "evaluate", "compete"):
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
    assert "--runs N simulations per evaluation (default 10; with --case-study 1)" in gen
    assert "--budget BUDGET evaluations allowed (default 50; with --case-study 200)" in gen
    assert "(default greedy; with --case-study suite)" in gen
    assert "then the defaults are --budget 200 --runs 1 --agent suite" in gen
    assert "--runs N simulations per evaluation (default 5)" in rep
    assert "the log's vehicle" in rep and "the log's vehicle" not in gen  # each says only its own UAV default
    assert "seed test with a reference log" in gen and "seed test with a reference log" not in rep
    assert "case-study" not in rep and "generate" not in rep.split("options:", 1)[1]
    assert ("default: the env's: Surrealist-Replicate-v0 5, Surrealist-Generate-v0 10, Surrealist-CaseStudy-v1 1"
            in _help("compare"))
    assert "(default 5; with --competition the edition's: 2024 5, 2025 3, 2026 5)" in _help("evaluate")


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
    (["train", "--problem", "missions", "--case-study", "mission2"],
     "--case-study: applies only to --problem case-study (missions draws its case studies)"),
    (["train", "--problem", "missions", "--obstacles", "2"], "--obstacles: applies only to --problem case-study"),
    (["train", "--problem", "missions", "--spread", "0.5"], "--spread: not with --problem missions"),
    (["train", "--learning-rate", "0"], "--learning-rate: expected a number in (0, 1), got 0"),
    (["train", "--problem", "case-study", "--case-study", "mission2", "--obstacles", "4"],
     "--obstacles: the competition allows 1 to 3 boxes, got 4"),
], ids=lambda v: " ".join(map(str, v)) if isinstance(v, list) else None)
def test_an_option_that_does_not_apply_is_refused_in_one_line(tmp_path, capsys, argv, message):
    store = tmp_path / "s.sqlite"
    store.write_bytes(b"not empty")
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{store}", str(store)) for a in argv]
    out = tmp_path / "out"
    written = ["--policy", str(out / "p.zip")] if argv[0] == "train" else ["--out", str(out)]
    assert main([*argv, *written]) == 2
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
        assert main([command, "--steps", "0", "--policy", str(tmp_path / "p.zip")]) == 2
        assert "--steps: expected a whole number >= 1, got 0" in _one_line_error(capsys)
    assert "--algorithm {ppo,sac}" in _help("train") and _help("train") == _help("train-ppo")


def test_train_with_sac_runs_a_few_steps_and_its_policy_searches(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    from search.registry import make_agent

    out = tmp_path / "sac.zip"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["train", "--algorithm", "sac", "--problem", "generate", "--steps", "4", "--episode-budget", "2",
                     "--policy", str(out)]) == 0
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


def test_train_on_drawn_case_studies_prints_a_compare_command_that_runs(tmp_path, capsys, monkeypatch):
    """``train --problem missions``: one policy for every mission, whose printed compare runs it on mission2."""
    pytest.importorskip("stable_baselines3")
    import shlex

    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["train", "--problem", "missions", "--steps", "4", "--episode-budget", "2",
                     "--policy", "m.zip"]) == 0
    printed = capsys.readouterr().out
    assert "trained ppo for 4 steps on drawn case studies" in printed
    assert json.loads((tmp_path / "m.json").read_text())["frame"] == "mission"
    command = next(line for line in printed.splitlines() if line.startswith("use it: ")).removeprefix("use it: ")
    argv = shlex.split(command)[1:]
    assert "suite,random,ppo-sample:m.zip" in argv and "mission2" in argv
    argv[argv.index("suite,random,ppo-sample:m.zip")] = "ppo-sample:m.zip"  # the policy only, to keep it short
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(argv + ["--repetitions", "1", "--budget", "2", "--out", str(tmp_path / "cmp")]) == 0


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


# --- compare --obstacles, --random-seed; the command train prints runs ------------------------------------------------
def _printed_compare(printed: str) -> list[str]:
    """The ``surrealist compare ...`` line a training printed, as argv for main()."""
    line = next(line for line in printed.splitlines() if line.startswith("use it: "))
    words = shlex.split(line[len("use it: "):])
    assert words[:2] == ["surrealist", "compare"] and "..." not in words, line
    return words[1:]


@pytest.mark.parametrize("problem", [
    ["--problem", "case-study", "--case-study", str(CASE_STUDIES / "mission2.yaml"), "--obstacles", "1"],
    ["--problem", "generate", "--seed", RQ2]], ids=["case-study with 1 box", "generate with a seed test"])
def test_the_compare_command_train_prints_runs_with_the_policy_it_saved(tmp_path, capsys, monkeypatch, problem):
    pytest.importorskip("stable_baselines3")
    monkeypatch.chdir(tmp_path)
    policy = Path("policies") / "p.zip"  # relative, as a user types it: the printed command runs from here
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["train", *problem, "--steps", "4", "--episode-budget", "2", "--policy", str(policy)]) == 0
        argv = _printed_compare(capsys.readouterr().out)
        assert f"ppo:{policy}" in argv[argv.index("--agents") + 1]
        # as printed, at a tiny scale: one search per agent of one evaluation of one run, in this process
        assert main([*argv, "--repetitions", "1", "--budget", "1", "--runs", "1", "--inline", "--out", "cmp"]) == 0
    settings = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    if "case-study" in problem:
        assert settings["env_id"] == "Surrealist-CaseStudy-v1" and settings["env_kwargs"]["obstacles"] == 1
    else:
        assert settings["env_id"] == "Surrealist-Generate-v0"
        assert settings["env_kwargs"]["seed_test"] == str(Path(RQ2).resolve())
    assert f"| ppo:{policy} |" in capsys.readouterr().out or "ppo" in (tmp_path / "cmp" / "compare.md").read_text()


def test_compare_flies_each_repetition_with_the_random_seed_plus_its_number(tmp_path, monkeypatch, capsys):
    import importlib

    search_compare = importlib.import_module("search.compare")  # the module (search.compare is also its function)
    seen = {}

    def fake(env_id, agents, **kw):
        seen.update(kw)
        raise _Stop("stop")

    monkeypatch.setattr(search_compare, "compare", fake)
    assert main(["compare", "--case-study", "mission1", "--obstacles", "2", "--agents", "random", "--random-seed",
                 "7", "--inline", "--out", str(tmp_path / "cmp")]) == 2
    assert seen["random_seed"] == 7 and seen["env_kwargs"]["obstacles"] == 2
    assert "--random-seed: expected a whole number >= 0, got -1" in (
        main(["compare", "--random-seed", "-1"]) == 2 and capsys.readouterr().err)


def test_search_compare_seeds_repetition_r_with_the_base_seed_plus_r(tmp_path):
    from search.compare import compare

    result = compare("Surrealist-Generate-v0", ["random"], repetitions=1, budget=1, runs=1, out=tmp_path / "cmp",
                     executor="inline", random_seed=5)
    settings = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    assert settings["random_seed"] == 5 and len(result.searches) == 1
    assert "env seed 5 + r, agent seed 5 + r" in (tmp_path / "cmp" / "compare.md").read_text()
