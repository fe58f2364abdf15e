"""The curated faces of fastep_core's sub-packages: every name they list is there, from the module they name."""

import importlib

import pytest

LAZY_FACES = ['fastep_core.experiments', 'fastep_core.planning.navigators', 'fastep_core.planning.recovery',
              'fastep_core.planning.safety', 'fastep_core.planning.shortest_path', 'fastep_core.planning.swarm']


@pytest.mark.parametrize('face', LAZY_FACES)
def test_every_listed_name_comes_from_its_home_module(face: str) -> None:
    package = importlib.import_module(face)
    homes = package._HOMES
    assert sorted(package.__all__) == sorted(name for names in homes.values() for name in names)
    for module, names in homes.items():
        home = importlib.import_module(f'{face}.{module}')
        for name in names:
            assert getattr(package, name) is getattr(home, name)
    assert set(package.__all__) <= set(dir(package))


@pytest.mark.parametrize('face', LAZY_FACES)
def test_an_unknown_name_is_an_attribute_error(face: str) -> None:
    with pytest.raises(AttributeError, match='no attribute'):
        importlib.import_module(face).__getattr__('no_such_name')
