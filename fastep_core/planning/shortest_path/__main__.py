"""`python -m fastep_core.planning.shortest_path`: the optimal length of every robot of the built-in scenarios.

Its own module: fastep_core.planning imports `optimal` (the Optimal-Kinematic navigator drives its path), so
`python -m ...shortest_path.optimal` ran a module already imported (runpy's RuntimeWarning).
"""

from fastep_core.planning.shortest_path.optimal import main

if __name__ == '__main__':
    raise SystemExit(main())
