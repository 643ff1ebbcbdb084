"""Pre-screening between the greedy's ask and tell on a tiny Generate env: real simulations only, skips logged,
seeded."""
import json

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy, Agent
from surrealist_gym.errors import SurrealistError
from surrealist_gym.sim.config import SimConfig
from surrogates.config import MEASURED_PRESCREEN, PrescreenConfig, SkipAccounting, measured_prescreen
from surrogates.dataset import Featurizer, load_dataset
from surrogates.models import SurrogateModel, train_model
from surrogates.prescreen import Prescreener
from surrogates.prescreened import Prescreened, wrap
from surrogates.racing import race_margin, tie_improvements
from surrogates.replay import replay_margin

BUDGET = 4


def _env():
    return gym.make("Surrealist-Generate-v0", budget=BUDGET, runs=1, executor="inline")


@pytest.fixture(scope="module")
def model(rq2_store, generate_featurizer):
    return train_model(load_dataset([rq2_store], generate_featurizer), generate_featurizer, "knn")


def _run(model, seed=0):
    env = _env()
    steps = []
    agent = Prescreened(AdaptiveGreedy("paper"), model, PrescreenConfig.of(threshold=0.5, max_skips=3), seed=seed)
    result = agent.run(env, seed=seed, callback=steps.append)
    return agent, result, steps, env


@pytest.fixture(scope="module")
def runs(model):
    return _run(model), _run(model)


def test_budget_counts_real_simulations_only(runs):
    agent, result, steps, env = runs[0]
    assert result.evaluations <= BUDGET
    assert env.unwrapped.evaluator.simulations == result.evaluations  # 1 run per evaluation; skips fly nothing
    assert agent.prescreener.skipped, "a strict threshold must skip candidates"
    for entry in agent.prescreener.skipped:
        assert entry["predicted_std"] > 0 and entry["told_fitness"] < result.best_fitness
    assert not any(s.get("skipped") for s in steps)  # the callback sees real steps only
    assert result.best_fitness == max(result.history)


def test_same_seed_same_search(runs):
    (a, ra, _, _), (b, rb, _, _) = runs
    assert ra.history == rb.history and a.prescreener.skipped == b.prescreener.skipped


def test_online_model_trains_as_evaluations_arrive():
    agent = Prescreened(AdaptiveGreedy("paper"), "online",
                        PrescreenConfig.of(min_points=2, retrain_every=1, kind="knn"), seed=1)
    result = agent.run(_env(), seed=1)
    assert result.evaluations <= BUDGET and agent.prescreener.retrains >= 1 and agent.prescreener.model is not None


def test_wrap(model, tmp_path):
    greedy = AdaptiveGreedy("paper")
    assert wrap(greedy, None) is greedy
    folder = model.save(tmp_path / "m")
    assert isinstance(wrap(greedy, str(folder), _env()), Prescreened)
    replicate = gym.make("Surrealist-Replicate-v0", budget=2, runs=1, executor="inline")
    with pytest.raises(SurrealistError, match="another mission"):
        wrap(greedy, str(folder), replicate)


def test_free_then_most_promising_candidates_first(model):
    candidates = [np.array([0.1, 0.0]), np.array([-0.1, 0.3]), np.array([0.0, -1.0])]  # the last one overlaps
    env = _env()
    _, info = env.reset(seed=0)
    prescreener = Prescreener(model, PrescreenConfig.of(rule="none"), seed=0)  # skips nothing: steps all three
    prescreener.start(env, info)
    batch = prescreener.evaluate(candidates)
    stepped = [next(i for i, c in enumerate(candidates) if c is a) for a, _, _ in batch.stepped]
    means = [model.predict_tests([env.unwrapped.test_for(a)])[0][0] for a in candidates[:2]]
    assert stepped[0] == 2  # free: the env rejects it without a simulation
    assert stepped[1:] == sorted([0, 1], key=lambda i: -means[i])
    fitness_of = {i: fitness for i, (_, fitness, _) in zip(stepped, batch.stepped)}
    assert list(batch.fitnesses) == [fitness_of[i] for i in range(3)]  # told in the order asked


def test_the_prescreener_sits_between_any_agents_ask_and_tell(model, runs):
    """An ask -> evaluate -> tell loop written by hand is the search Prescreened runs; neither is an agent."""
    config = PrescreenConfig.of(threshold=0.5, max_skips=3)
    env = _env()
    _, info = env.reset(seed=0)
    prescreener, greedy = Prescreener(model, config, seed=0), AdaptiveGreedy("paper", seed=0)
    prescreener.start(env, info)
    greedy.setup(prescreener.agent_env, info)
    history = [info["fitness"]]
    while not (prescreener.stop() or greedy.stop()):
        actions = greedy.ask()
        batch = prescreener.evaluate(actions)
        history += [fitness for _, fitness, _ in batch.stepped]
        greedy.tell(actions[:len(batch.fitnesses)], batch.fitnesses, batch.infos)
    agent, result, _, _ = runs[0]
    assert tuple(history) == result.history and prescreener.skipped == agent.prescreener.skipped
    assert not isinstance(agent, Agent) and not hasattr(prescreener, "ask")


def test_replay_margin_replays_each_search_in_order():
    # two searches of 12 evaluations: real fitness rises each step, the low-fidelity fitness of each improvement
    # falls short of its incumbent's by 0, 1, ..., 10 (search 0) and 0 (search 1: it must not inherit search 0's best)
    real = np.concatenate([np.arange(12.0), np.arange(12.0) - 100])
    low = np.concatenate([-np.cumsum(np.r_[0.0, np.arange(11.0)]), np.zeros(12)])
    groups = np.repeat([0, 1], 12)
    shortfalls = np.r_[np.arange(11.0), np.zeros(11)]
    assert replay_margin(low, real, groups, miss_rate=0.1) == pytest.approx(np.quantile(shortfalls, 0.9))
    assert replay_margin(low[:8], real[:8], groups[:8]) is None  # too few improvements to calibrate


@pytest.fixture(scope="module")
def lowfi_model(rq1_lowfi_dataset, replicate_lowfi_featurizer):
    return train_model(rq1_lowfi_dataset, replicate_lowfi_featurizer, "knn")


def test_lowfi_rule_skips_candidates_the_coarse_flight_finds_clearly_worse(lowfi_model):
    env = gym.make("Surrealist-Replicate-v0", budget=6, runs=1, executor="inline")
    agent = Prescreened(AdaptiveGreedy("authors"), lowfi_model, PrescreenConfig.of(miss_rate=0.5), seed=0)
    result = agent.run(env, seed=0)
    screened = agent.prescreener
    assert screened.rule == "lowfi" and screened.margin is not None  # auto: the model's stores calibrate a margin
    assert result.evaluations <= 6 and env.unwrapped.evaluator.simulations == result.evaluations
    assert screened.skipped, "a margin at the median of past improvements must skip candidates"
    for entry in screened.skipped:
        assert entry["rule"] == "lowfi" and entry["lowfi_shortfall"] > screened.margin
        assert entry["told_fitness"] < result.best_fitness


def test_lowfi_rule_needs_low_fidelity_features(model):
    agent = Prescreened(AdaptiveGreedy("paper"), model, PrescreenConfig.of(rule="lowfi"), seed=0)
    with pytest.raises(SurrealistError, match="low-fidelity"):
        agent.run(_env(), seed=0)


def test_racing_drops_candidates_whose_first_runs_fall_short():
    env = gym.make("Surrealist-Generate-v0", budget=6, runs=3, executor="inline")
    config = PrescreenConfig.of(rule="ei", first_runs=1, race_margin=0.0, lowfi=False)
    agent = Prescreened(AdaptiveGreedy("paper"), "online", config, seed=0)
    result = agent.run(env, seed=0)
    raced = [s for s in agent.prescreener.skipped if s["rule"] == "race"]
    assert raced, "a zero margin must drop candidates whose first run is worse than the incumbent's"
    for entry in raced:
        assert entry["race_shortfall"] > 0 and entry["told_fitness"] < result.best_fitness
    sims = env.unwrapped.evaluator.simulations
    assert sims == 3 * result.evaluations + len(raced)  # a dropped candidate cost its first run only
    assert env.unwrapped.budget_left >= 0


def test_racing_in_stages_drops_a_candidate_at_the_first_stage_it_falls_behind():
    env = gym.make("Surrealist-Generate-v0", budget=6, runs=3, executor="inline")
    # against the incumbent's same first runs: against its fitness, a riskiest-run score that passes stage 1 at a
    # zero margin passes stage 2 too (the riskiest of two runs scores at least the first's)
    config = PrescreenConfig.of(rule="ei", first_runs=(1, 2), race_margin=0.0, lowfi=False, race_against="paired")
    agent = Prescreened(AdaptiveGreedy("paper"), "online", config, seed=0)
    result = agent.run(env, seed=0)
    assert agent.prescreener.race_margins == {1: 0.0, 2: 0.0}
    raced = [s for s in agent.prescreener.skipped if s["rule"] == "race"]
    assert {s["first_runs"] for s in raced} == {1, 2}, "both stages drop candidates at a zero margin"
    assert all(s["race_shortfall"] > 0 for s in raced)
    assert len({s["test_key"] for s in raced}) == len(raced)  # asked again, a dropped test is a free memo answer
    assert env.unwrapped.evaluator.simulations == 3 * result.evaluations + sum(s["first_runs"] for s in raced)
    assert result.simulations == env.unwrapped.evaluator.simulations > env.unwrapped.simulations  # raced runs count


def test_racing_stages_must_increase():
    assert PrescreenConfig.of(first_runs=(1, 2, 3)).race.stages == (1, 2, 3)
    assert PrescreenConfig.of(first_runs=2).race.stages == (2,) and PrescreenConfig().race.stages == ()
    with pytest.raises(ValueError, match="increasing"):
        PrescreenConfig.of(first_runs=(2, 1))


def test_skips_spend_the_inner_agents_budget(model):
    # a screen that skips every candidate: with SkipAccounting.BUDGET the greedy runs out of (its) budget after as many
    # candidates as the budget allows, having simulated only the seed test; the env's budget is left unspent
    env = gym.make("Surrealist-Generate-v0", budget=5, runs=1, executor="inline")
    config = PrescreenConfig.of(rule="pi", threshold=1.0, max_skips=10**6, skips=SkipAccounting.BUDGET)
    agent = Prescreened(AdaptiveGreedy("paper"), model, config, seed=0)
    result = agent.run(env, seed=0)
    assert len(agent.prescreener.skipped) == 4 and agent.prescreener.unspent == pytest.approx(4.0)
    assert result.stop_reason.startswith("budget spent") and env.unwrapped.budget_left == 4
    assert env.unwrapped.evaluator.simulations == 1
    assert PrescreenConfig.of(skips="budget").skips is SkipAccounting.BUDGET
    with pytest.raises(ValueError, match="prescreen skips: expected one of"):
        PrescreenConfig.of(skips="sometimes")


def test_the_inner_agent_stops_where_its_budget_with_skips_counted_ends():
    # every candidate is dropped after its first run (a margin below any shortfall): the greedy is told exactly as
    # many candidates as the budget holds after the seed test, as the env would cut it off without screening
    env = gym.make("Surrealist-Generate-v0", budget=4, runs=2, executor="inline")
    config = PrescreenConfig.of(rule="none", first_runs=1, race_margin=-1e9, lowfi=False, skips=SkipAccounting.BUDGET)
    agent = Prescreened(AdaptiveGreedy("paper"), "online", config, seed=0)
    result = agent.run(env, seed=0)
    assert len(agent.prescreener.skipped) == 3 and result.stop_reason.startswith("budget spent")
    assert env.unwrapped.budget_left > 0  # the simulations saved are left unspent (no verify pass)


class _AsksTwice(AdaptiveGreedy):
    """Asks the same candidate twice in one ask, once."""

    def _ask(self):
        return [] if self._stop_reason else [np.full(len(self._env.mutators), 0.3)] * 2

    def _tell(self, actions, fitnesses, infos):
        self.told = list(zip(fitnesses, infos))
        self._finish("asked")


def test_a_test_asked_twice_in_one_ask_is_flown_once_and_then_a_memo_answer():
    env = gym.make("Surrealist-Generate-v0", budget=4, runs=2, executor="inline", sim_config={"common_noise": True})
    inner = _AsksTwice("paper")
    agent = Prescreened(inner, "online", PrescreenConfig.of(rule="none", first_runs=1, lowfi=False), seed=0)
    agent.run(env, seed=0)
    (first, _), (second, info) = inner.told
    assert second == first and info["memo"] and not agent.prescreener.skipped  # not raced against itself


def test_racing_drops_ties_under_common_noise():
    # with common random numbers, moving the RQ2 box along the path (its first mutator, y) leaves the flights and
    # their scores unchanged: such candidates tie the incumbent on their first run and are dropped after it
    env = gym.make("Surrealist-Generate-v0", budget=6, runs=3, executor="inline",
                   sim_config={"common_noise": True})  # a mapping, as `surrealist compare --common-noise` passes it
    assert env.unwrapped.evaluator.sim_config.common_noise
    config = PrescreenConfig.of(rule="ei", first_runs=1, race_margin=1e9, lowfi=False)  # no drop by shortfall
    agent = Prescreened(AdaptiveGreedy("paper"), "online", config, seed=0)
    result = agent.run(env, seed=0)
    ties = [s for s in agent.prescreener.skipped if s["rule"] == "race"]
    assert ties and all(s["tie"] and s["race_shortfall"] == pytest.approx(0.0, abs=1e-6) for s in ties)
    assert env.unwrapped.evaluator.simulations == 3 * result.evaluations + len(ties)


def test_racing_needs_fewer_first_runs_than_runs():
    env = gym.make("Surrealist-Generate-v0", budget=2, runs=2, executor="inline")
    agent = Prescreened(AdaptiveGreedy("paper"), "online", PrescreenConfig.of(first_runs=2, lowfi=False), seed=0)
    with pytest.raises(SurrealistError, match="first_runs"):
        agent.run(env, seed=0)


def test_race_margin_is_calibrated_on_the_first_runs_of_real_stores(rq1_stores, replicate_featurizer):
    data = load_dataset(rq1_stores, replicate_featurizer)
    assert data.first_runs.shape == (len(data), 4) and np.isfinite(data.first_runs).all()
    model = train_model(data, replicate_featurizer, "knn", seed=0)
    margins = [race_margin(model, k) for k in (1, 4)]
    assert all(m is not None and m >= 0 for m in margins)
    assert margins[0] > margins[1]  # one run of five is a noisier proxy of the fitness than four
    assert race_margin(model, 5) is None  # no proxy for all five runs: that is the fitness itself


def test_a_stop_the_skips_caused_is_verified_by_simulation(model):
    # a screen that skips every candidate: the greedy gives up with budget left; the verify pass restarts it from
    # the best test with screening off and spends the budget on real simulations
    ends = {}
    for verify in (False, True):
        env = gym.make("Surrealist-Generate-v0", budget=3, runs=1, executor="inline")
        config = PrescreenConfig.of(rule="pi", threshold=1.0, max_skips=10**6, verify_stop=verify)
        agent = Prescreened(AdaptiveGreedy("paper"), model, config, seed=0)
        result = agent.run(env, seed=0)
        ends[verify] = (agent, result, env.unwrapped)
    agent, result, env = ends[False]
    assert agent.prescreener.skipped and agent.verified_at is None
    assert result.stop_reason == "no mutator improves the best" and env.budget_left > 0
    agent, result, env = ends[True]
    assert agent.verified_at == 1 and env.budget_left <= 0 and result.evaluations == 3
    assert all(s["after_evaluations"] <= agent.verified_at for s in agent.prescreener.skipped)  # none after it
    assert env.evaluator.simulations == 3  # the seed test, then the two candidates of the verify pass


def test_a_dropped_candidate_tells_its_first_runs_trajectory_and_how_many_runs():
    """The authors' greedy compares trajectories in its plateau test: a dropped candidate tells the averaged
    trajectory of the runs it flew and their number, so the greedy compares it with the best's same first runs."""
    told = []

    class Recording(AdaptiveGreedy):
        def tell(self, actions, fitnesses, infos):
            told.extend(infos)
            return super().tell(actions, fitnesses, infos)

    env = gym.make("Surrealist-Replicate-v0", budget=4, runs=3, executor="inline",
                   sim_config={"common_noise": True})
    config = PrescreenConfig.of(rule="none", first_runs=(1, 2), race_margin=0.0, lowfi=False)
    agent = Prescreened(Recording("authors"), "online", config, seed=0)
    agent.run(env, seed=0)
    dropped = [i for i in told if i.get("skipped") and not i.get("memo")]
    assert dropped, "a zero margin drops candidates"
    assert all(len(i["statuses"]) in (1, 2) and i["trajectory"].shape[1] == 3 for i in dropped)


def test_a_model_used_in_the_other_noise_mode_is_flagged(model, tmp_path):
    # the knn model learnt from an RQ2 store flown with each test's own noise; a search under common random numbers
    # is told, in one line, that its racing margins were calibrated in the other mode
    assert model.common_noise is False
    folder = model.save(tmp_path / "m")
    assert SurrogateModel.load(folder).common_noise is False
    crn = gym.make("Surrealist-Generate-v0", budget=2, runs=2, executor="inline", sim_config={"common_noise": True})
    with pytest.warns(UserWarning, match="each test's own noise, this search flies common noise"):
        Prescreened(AdaptiveGreedy("paper"), SurrogateModel.load(folder), seed=0).run(crn, seed=0)
    from surrealist_gym.cli import main
    out = tmp_path / "crn"
    with pytest.warns(UserWarning, match=f"^{folder}: trained on .* or match --common-noise"):  # the CLI prints
        assert main(["generate", "--budget", "2", "--runs", "2", "--workers", "1", "--common-noise",  # "warning: "
                     "--surrogate", str(folder), "--out", str(out)]) == 0


def test_an_online_model_keeps_the_noise_mode_it_learnt_from():
    env = gym.make("Surrealist-Generate-v0", budget=3, runs=1, executor="inline", sim_config={"common_noise": True})
    agent = Prescreened(AdaptiveGreedy("paper"), "online",
                        PrescreenConfig.of(min_points=2, retrain_every=1, kind="knn", lowfi=False), seed=0)
    agent.run(env, seed=0)
    assert agent.prescreener.model is not None and agent.prescreener.model.common_noise is True


def test_ties_are_raced_only_where_no_tie_improved_in_the_training_stores():
    # two searches replayed in the order evaluated: in the first, an improvement (-40 over -50) tied its incumbent's
    # first run (a lower box under common noise: run 1 unchanged, the others better); in the second, no tie improved
    first = [[-60.0, -55.0], [-60.0, -45.0], [-70.0, -65.0],  # search 0: the seed, a tie that improves, a worse one
             [-60.0, -55.0], [-60.0, -58.0], [-50.0, -48.0]]  # search 1: the seed, a tie that does not, an improvement
    fitness, groups = [-50.0, -40.0, -66.0, -50.0, -52.0, -45.0], [0, 0, 0, 1, 1, 1]
    assert tie_improvements(first, fitness, groups) == 1
    assert tie_improvements(first[3:], fitness[3:], groups[3:]) == 0
    assert tie_improvements(np.full((6, 0), np.nan), fitness, groups) == 0  # stores without first runs

    featurizer = Featurizer.for_problem("generate")

    def drops_ties(rows) -> bool:
        features = np.random.default_rng(0).normal(size=(len(rows), len(featurizer.names)))
        model = SurrogateModel(featurizer, "knn").fit(features, [fitness[i] for i in rows], [groups[i] for i in rows],
                                                      [first[i] for i in rows])
        env = gym.make("Surrealist-Generate-v0", budget=1, runs=3, executor="inline",
                       sim_config={"common_noise": True})
        _, info = env.reset(seed=0)
        prescreener = Prescreener(model, PrescreenConfig.of(rule="none", first_runs=1), seed=0)
        prescreener.start(env, info)
        return prescreener.calibration.race.drop_ties

    assert drops_ties([3, 4, 5]) and not drops_ties([0, 1, 2, 3, 4, 5])


def test_surrogate_alone_runs_the_measured_settings_for_its_noise_mode(model, tmp_path, capsys):
    """`--surrogate MODEL` without expert flags: an own-noise model races a generation in stages below its 4 runs,
    the skips spending the greedy's budget and the stop verified (the setting measured for it); the settings are
    recorded in run.json. An expert flag keeps the user's settings."""
    from surrealist_gym.cli import main

    folder = model.save(tmp_path / "m")
    out = tmp_path / "gen"
    assert main(["generate", "--budget", "2", "--runs", "4", "--workers", "1", "--surrogate", str(folder),
                 "--out", str(out)]) == 0
    options = json.loads((out / "run.json").read_text())
    assert options["first_runs"] == [1, 2, 3] and options["skips_spend_budget"] and options["verify_stop"]
    assert "pre-screening as measured" in capsys.readouterr().err
    out2 = tmp_path / "gen2"
    assert main(["generate", "--budget", "2", "--runs", "4", "--workers", "1", "--surrogate", str(folder),
                 "--first-runs", "1", "--out", str(out2)]) == 0
    assert json.loads((out2 / "run.json").read_text())["first_runs"] == [1]


def test_a_search_in_the_measured_shape_keeps_its_figures(model):
    """Common noise, racing in stages, skips spending the greedy's budget, the unscreened restart and retraining: the
    search the savings of docs/results.md were measured with. A regression test: these figures come from the code
    that measured them, so a change that moves them changes what those savings mean."""
    told = []

    class Recording(AdaptiveGreedy):
        def tell(self, actions, fitnesses, infos):
            told.extend((f, bool(i.get("skipped"))) for f, i in zip(fitnesses, infos))
            return super().tell(actions, fitnesses, infos)

    env = gym.make("Surrealist-Generate-v0", budget=5, runs=3, executor="inline",
                   sim_config=SimConfig(common_noise=True))  # the bare UAV these figures were first measured on
    config = PrescreenConfig.of(threshold=0.3, first_runs=(1, 2), race_margin=0.5, skips="budget", verify_stop=True,
                                retrain_every=2)
    agent = Prescreened(Recording("paper"), model, config, seed=0)
    result = agent.run(env, seed=0)
    # on the compiled physics; PyBullet's figures before the ground hold differed by < 3e-4 relative, the same
    # skips and steps
    skips = [-21.8917906682006, -21.8917906682006, -23.088361699353417]
    steps = [-17.847066464884403, -17.888443853716584, -17.89179064630881, -21.89179064630881, -12.77611807274284]
    assert [f for f, _ in told] == pytest.approx(skips + steps, rel=1e-9, abs=0)
    assert [skipped for _, skipped in told] == [True] * 3 + [False] * 5
    assert result.history == pytest.approx([-21.89179064630881, *steps], rel=1e-9, abs=0)
    assert (result.evaluations, result.evaluations_to_best, result.simulations) == (5, 5, 15)
    assert result.stop_reason == "budget spent" and agent.verified_at == 2
    screened = agent.prescreener
    assert [s["rule"] for s in screened.skipped] == ["ei"] * 3 and screened.retrains == 1


def test_the_measured_settings_live_with_the_surrogates():
    own = dict(measured_prescreen(False, "generate", runs=10))
    assert own == {"first_runs": (1, 2, 3, 4), "skips": SkipAccounting.BUDGET, "verify_stop": True}
    settings = measured_prescreen(True, "replicate", runs=3)  # racing stages at or above the runs are left out
    config = PrescreenConfig.of(**settings)
    assert (config.screen.rule, config.race.stages, config.skips, config.verify_stop) == (
        "none", (1, 2), SkipAccounting.BUDGET, True)
    assert measured_prescreen(None, "generate", runs=10) == {}  # a model whose noise mode is unknown
    with pytest.raises(TypeError):
        MEASURED_PRESCREEN[(True, "generate")]["verify_stop"] = False
