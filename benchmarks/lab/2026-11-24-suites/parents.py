import sys, time, collections, json, math
import numpy as np
import gymnasium as gym, surrealist_gym
from surrealist_gym.competition.suite_env import RecordSuite
from search.novelty import SuiteSearch
mission, seed, sigma, rate, explore = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
env = RecordSuite(gym.make("Surrealist-CaseStudy-v1", case_study=mission, budget=200, random_seed=seed, executor="inline"))
class Logged(SuiteSearch):
    def _ask(self):
        self._last_parent = None
        c = self.config
        if not self._parents or self.rng.random() < c.explore:
            return [self.rng.uniform(self._low, self._high)]
        out = super()._ask.__wrapped__(self) if hasattr(super()._ask, "__wrapped__") else None
        return out
agent = SuiteSearch(seed=seed, sigma=sigma, rate=rate, explore=explore)
pairs = []
orig_ask = agent._ask
def ask():
    n_before = [p[2] for p in agent._parents]
    out = orig_ask()
    n_after = [p[2] for p in agent._parents]
    agent._lp = next((p[1] for p, a, b in zip(agent._parents, n_after, n_before) if a != b), None)
    return out
agent._ask = ask
log = []
def cb(info):
    if info.get("invalid") or info.get("memo"): 
        log.append(("inv", agent._lp)); return
    log.append((min(info["competition_distances"]), agent._lp))
t=time.time()
r = agent.run(env, seed=seed, callback=cb)
kids = [(d, p) for d, p in log if p is not None]
inv = sum(1 for d, p in kids if d == "inv")
fk = [(d, p) for d, p in kids if d != "inv"]
print(mission, seed, sigma, rate, explore, f"{time.time()-t:.0f}s suite={len(env.suite)} fails={sum(1 for d,p in log if d!='inv' and d<1.5)}",
 "children", len(kids), "invalid", inv,
 "child-of-fail fail rate", round(np.mean([d<1.5 for d,p in fk if p<1.5]) if any(p<1.5 for d,p in fk) else -1,2),
 "child-of-near fail rate", round(np.mean([d<1.5 for d,p in fk if p>=1.5]) if any(p>=1.5 for d,p in fk) else -1,2),
 "explore fail rate", round(np.mean([d<1.5 for d,p in log if p is None and d!='inv']),3))
