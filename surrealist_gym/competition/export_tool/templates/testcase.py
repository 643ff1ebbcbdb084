"""A test of the competition's interface: a case study with obstacles, executed by the Aerialist agent that the
``AGENT`` environment variable names (``local``, ``docker`` or ``k8s``; default ``docker``), as the competition's
snippet does, so the competition's platform runs it on its own infrastructure."""
import copy
import logging

from aerialist.px4.aerialist_test import AerialistTest, AgentConfig
from decouple import config

AGENT = config("AGENT", default=AgentConfig.DOCKER)

logger = logging.getLogger(__name__)


def agent_class():
    """Aerialist's agent class for ``AGENT``."""
    if AGENT == AgentConfig.LOCAL:
        from aerialist.px4.local_agent import LocalAgent
        return LocalAgent
    if AGENT == AgentConfig.DOCKER:
        from aerialist.px4.docker_agent import DockerAgent
        return DockerAgent
    if AGENT == AgentConfig.K8S:
        from aerialist.px4.k8s_agent import K8sAgent
        return K8sAgent
    raise ValueError(f"AGENT={AGENT!r}: expected {AgentConfig.LOCAL}, {AgentConfig.DOCKER} or {AgentConfig.K8S}")


class TestCase:
    """A case study with the given obstacles, flown by the Aerialist agent ``AGENT`` names."""
    def __init__(self, casestudy, obstacles):
        self.test = copy.deepcopy(casestudy)
        self.test.simulation.obstacles = obstacles

    def execute(self):
        """Fly the test once; its trajectory (Aerialist's Trajectory). Sets ``log_file``."""
        logger.info("executing the test with %s", AGENT)
        self.test_results = agent_class()(self.test).run()
        self.trajectory = self.test_results[0].record
        self.log_file = self.test_results[0].log_file
        return self.trajectory

    def get_distances(self):
        """The flight's least distance to each obstacle [m], as the competition measures it."""
        return [self.trajectory.min_distance_to_obstacles([o]) for o in self.test.simulation.obstacles]

    def plot(self):
        """Plot the flight with its obstacles; sets ``plot_file``. Aerialist's plot moved from AerialistTest to
        Plot.plot_test: whichever the Aerialist at hand has."""
        plot = getattr(AerialistTest, "plot", None)
        if plot is None:
            from aerialist.px4.plot import Plot
            plot = Plot.plot_test
        self.plot_file = plot(self.test, self.test_results)

    def save_yaml(self, path):
        """Write the test as an Aerialist YAML to ``path``."""
        self.test.to_yaml(path)
