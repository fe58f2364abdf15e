"""Hypothesis profiles for the property tests.

`ci` (the default, what `make test` runs): derandomised, so every run tries the same examples and a red build
means the code changed, not the draw. `explore` (`make fuzz`): fresh random examples each run, to find new
counterexamples by hand; add any it finds to the test as an `@example`.
"""

import os

from hypothesis import settings

settings.register_profile('ci', derandomize=True)
settings.register_profile('explore', derandomize=False)
settings.load_profile(os.environ.get('HYPOTHESIS_PROFILE', 'ci'))
