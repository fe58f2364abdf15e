"""Swarm optimizers for one planned step: FAStep (the paper's), the standard firefly algorithm and ACO_R.

All three minimise a vectorised objective (an (m, d) array of candidates in, an (m,) array of values out) over
a box, take every random draw from one numpy Generator (same seed, same result), and return an
`OptimizeResult`.
"""

from fastep_core.optimize.aco import aco_r
from fastep_core.optimize.fastep import fastep, fastep_iterations
from fastep_core.optimize.firefly import firefly
from fastep_core.optimize.result import OptimizeResult

__all__ = ['OptimizeResult', 'fastep', 'fastep_iterations', 'firefly', 'aco_r']
