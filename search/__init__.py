"""Search agents that propose test mutations through the surrealist_gym envs."""
