"""Benchmark: FAStep against the standard firefly algorithm, niapy's FireflyAlgorithm and differential evolution.

The paper credits FAStep's stepping-ahead move with escaping local minima better than the standard firefly
algorithm. Here the optimizers meet on sphere, Rastrigin, Ackley, Rosenbrock and Griewank (minimum 0) in 2-D and
10-D at the SAME number of objective evaluations, over 30 seeds: median best value and median wall time per run.
Every objective goes through `Budget`, which counts evaluated points, scores points beyond the budget +inf and
stops the optimizer; each is given iteration limits it cannot reach first, and its result is the best value
`Budget` saw. Contenders: FAStep and the firefly algorithm with the paper's Table 1 parameters (and 'n20' variants
with niapy's population and damping, 'FAStep k5' with attraction_sample=5, 'FAStep merged' with merged_moves),
niapy's FireflyAlgorithm with its defaults, and scipy's differential_evolution (best1bin, no polishing).
niapy evaluates one point per Python call, so its wall times say more about the implementation than the algorithm.

    python -m benchmarks.optimizers [--budget 20000] [--seeds 30] [--dims 2 10] [--workers 2] [--out FILE]

(needs niapy, a test/bench-only dependency pinned in requirements-test.txt).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from fastep_core.cli import Parser, progress_bar
from fastep_core.experiments.batches import pool_context
from fastep_core.optimize import fastep, firefly

FloatArray = np.ndarray
Function = Callable[[FloatArray], FloatArray]


# ----------------------------------------------------------------------------------------- test functions

def sphere(X: FloatArray) -> FloatArray:
    return np.sum(X * X, axis=1)


def rastrigin(X: FloatArray) -> FloatArray:
    return 10.0 * X.shape[1] + np.sum(X * X - 10.0 * np.cos(2.0 * np.pi * X), axis=1)


def ackley(X: FloatArray) -> FloatArray:
    d = X.shape[1]
    return (-20.0 * np.exp(-0.2 * np.sqrt(np.sum(X * X, axis=1) / d))
            - np.exp(np.sum(np.cos(2.0 * np.pi * X), axis=1) / d) + 20.0 + math.e)


def rosenbrock(X: FloatArray) -> FloatArray:
    return np.sum(100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2, axis=1)


def griewank(X: FloatArray) -> FloatArray:
    i = np.sqrt(np.arange(1, X.shape[1] + 1))
    return 1.0 + np.sum(X * X, axis=1) / 4000.0 - np.prod(np.cos(X / i), axis=1)


FUNCTIONS: dict[str, tuple[Function, float]] = {   # name: (function, half-width of the box [-w, w] or bounds)
    'sphere': (sphere, 5.12),
    'rastrigin': (rastrigin, 5.12),
    'ackley': (ackley, 32.768),
    'rosenbrock': (rosenbrock, 0.0),        # bounds [-5, 10]
    'griewank': (griewank, 600.0),
}


def bounds_of(name: str, d: int) -> FloatArray:
    if name == 'rosenbrock':
        return np.tile([-5.0, 10.0], (d, 1))
    w = FUNCTIONS[name][1]
    return np.tile([-w, w], (d, 1))


# ----------------------------------------------------------------------------------------- the budget

class BudgetExhausted(Exception):
    """Raised by Budget once every allowed evaluation has been spent."""


class Budget:
    """Counts evaluated points, evaluates at most `max_evals` of them, remembers the best value."""

    def __init__(self, fun: Function, max_evals: int, *, stop: bool = True) -> None:
        self.fun, self.max_evals, self.stop = fun, max_evals, stop
        self.nfev = 0
        self.best = math.inf

    def __call__(self, X: FloatArray) -> FloatArray:
        X = np.asarray(X, dtype=float)
        left = self.max_evals - self.nfev
        if left <= 0 and self.stop:
            raise BudgetExhausted
        f = np.full(X.shape[0], np.inf)
        k = max(0, min(X.shape[0], left))
        if k:
            f[:k] = self.fun(X[:k])
            self.nfev += k
            self.best = min(self.best, float(f[:k].min()))
        return f


# ----------------------------------------------------------------------------------------- the optimizers

def _swarm(method: Callable[..., object], **params: float) -> Callable[[Budget, FloatArray, int], None]:
    def run(budget: Budget, bounds: FloatArray, seed: int) -> None:
        method(budget, bounds, max_iter=10**6, patience=10**6, rng=np.random.default_rng(seed), **params)
    return run


def _run_de(budget: Budget, bounds: FloatArray, seed: int) -> None:
    from scipy.optimize import differential_evolution
    differential_evolution(lambda x: budget(np.atleast_2d(x.T)), bounds, maxiter=10**6, tol=0.0, atol=0.0,
                           polish=False, vectorized=True, updating='deferred', init='latinhypercube',
                           rng=np.random.default_rng(seed))


def _run_niapy(budget: Budget, bounds: FloatArray, seed: int) -> None:
    from niapy.algorithms.basic import FireflyAlgorithm
    from niapy.problems import Problem
    from niapy.task import Task

    class Wrapped(Problem):
        def _evaluate(self, x: FloatArray) -> float:
            return float(budget(x[None, :])[0])

    budget.stop = False          # niapy stops itself at max_evals; a raise would escape its loop
    task = Task(problem=Wrapped(bounds.shape[0], bounds[:, 0], bounds[:, 1]), max_evals=budget.max_evals)
    FireflyAlgorithm(seed=seed).run(task)


OPTIMIZERS: dict[str, Callable[[Budget, FloatArray, int], None]] = {
    'FAStep': _swarm(fastep),
    'firefly': _swarm(firefly),
    'FAStep n20': _swarm(fastep, n_fireflies=20, alpha_damping=0.97),
    'FAStep k5': _swarm(fastep, attraction_sample=5),
    'FAStep merged': _swarm(fastep, merged_moves=True),
    'firefly n20': _swarm(firefly, n_fireflies=20, alpha_damping=0.97),
    'niapy FA': _run_niapy,
    'DE (scipy)': _run_de,
}


def run_one(job: tuple[str, int, str, int, int]) -> tuple[str, int, str, int, float, float, int]:
    """(function, d, optimizer, seed, budget) -> (..., best value, wall seconds, evaluations used)."""
    name, d, optimizer, seed, max_evals = job
    budget = Budget(FUNCTIONS[name][0], max_evals)
    start = time.perf_counter()
    try:
        OPTIMIZERS[optimizer](budget, bounds_of(name, d), seed)
    except BudgetExhausted:
        pass
    return name, d, optimizer, seed, budget.best, time.perf_counter() - start, budget.nfev


def run_all(dims: Sequence[int], seeds: int, max_evals: int, workers: int,
            optimizers: Sequence[str] = tuple(OPTIMIZERS),
            progress: bool | None = None) -> list[tuple[str, int, str, int, float, float, int]]:
    """Every (function, d, optimizer, seed) run; `progress` as fastep_core.cli.progress_bar's `show`."""
    jobs = [(f, d, o, s, max_evals) for f in FUNCTIONS for d in dims for o in optimizers for s in range(seeds)]
    order = np.random.default_rng(0).permutation(len(jobs))     # spread background load over optimizers
    jobs = [jobs[k] for k in order]
    out = []
    with pool_context().Pool(workers) as pool, progress_bar(len(jobs), 'optimizers', progress) as bar:
        for row in pool.imap_unordered(run_one, jobs, chunksize=4):
            out.append(row)
            bar.update()
    return out


def markdown(rows: Sequence[tuple[str, int, str, int, float, float, int]], dims: Sequence[int], seeds: int,
             max_evals: int, optimizers: Sequence[str], command: str) -> str:
    lines = ['## Optimizers', '', '```', command, '```', '',
             f'Median over {seeds} seeds of the best value found (all minima are 0) with {max_evals:,} '
             'objective evaluations, and in brackets the median wall time per run in ms. Bold: lowest median '
             'value in the row.', '',
             '| function | d | ' + ' | '.join(optimizers) + ' |', '|---|---|' + '---|' * len(optimizers)]
    for f in FUNCTIONS:
        for d in dims:
            med, wall = {}, {}
            for o in optimizers:
                sel = [r for r in rows if r[0] == f and r[1] == d and r[2] == o]
                med[o] = float(np.median([r[4] for r in sel]))
                wall[o] = float(np.median([r[5] for r in sel])) * 1e3
            best = min(med.values())
            cells = [(f'**{med[o]:.3g}**' if med[o] == best else f'{med[o]:.3g}') + f' ({wall[o]:.0f} ms)'
                     for o in optimizers]
            lines.append(f'| {f} | {d} | ' + ' | '.join(cells) + ' |')
    used = {o: int(np.median([r[6] for r in rows if r[2] == o])) for o in optimizers}
    lines += ['', 'Median evaluations used: ' + ', '.join(f'{o} {n:,}' for o, n in used.items()) + '.']
    return '\n'.join(lines) + '\n'


def kept_sections(path: Path) -> str:
    """The hand-written sections after the generated table of an existing file (from its second '## ' heading
    on), so that regenerating the table does not drop them."""
    try:
        old = path.read_text()
    except OSError:
        return ''
    at = old.find('\n## ', 1)
    return '' if at < 0 else old[at:]


def main(argv: Sequence[str] | None = None) -> int:
    p = Parser(prog='python -m benchmarks.optimizers', description=__doc__.splitlines()[0])
    p.add_argument('--budget', type=int, default=20_000, help='objective evaluations per run (default 20000)')
    p.add_argument('--seeds', type=int, default=30, help='seeds per function and optimizer (default 30)')
    p.add_argument('--dims', type=int, nargs='+', default=[2, 10], help='dimensions (default 2 10)')
    p.add_argument('--workers', type=int, default=2, help='worker processes (default 2)')
    p.add_argument('--optimizers', nargs='+', default=list(OPTIMIZERS), choices=list(OPTIMIZERS),
                   metavar='NAME', help=f'subset of: {", ".join(OPTIMIZERS)}')
    p.add_argument('--out', type=Path, help='also write the Markdown table to this file')
    p.add_argument('--progress', action='store_true',
                   help='show the progress bar on stderr even when it is not a terminal (e.g. a log file)')
    args = p.parse_args(argv)
    if args.budget < 100 or args.seeds < 1 or args.workers < 1 or min(args.dims) < 1:
        p.error('--budget must be >= 100, --seeds, --workers and --dims >= 1')
    rows = run_all(args.dims, args.seeds, args.budget, args.workers, args.optimizers,
                   progress=True if args.progress else None)
    command = 'python -m benchmarks.optimizers ' + ' '.join(sys.argv[1:] if argv is None else argv)
    text = markdown(rows, args.dims, args.seeds, args.budget, args.optimizers, command.strip())
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + kept_sections(args.out))
        print(f'wrote {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
