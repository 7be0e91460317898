"""The design-space explorer: a design of experiments, surrogates of every output, constrained
multi-objective search on them, and every proposed design verified by the real pipeline."""
