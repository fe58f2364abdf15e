"""The package as a ROS user gets it: `colcon build`, `ros2 run`, rosdep's keys, pip's requirements.

`colcon build` runs colcon from PyPI (colcon-core, colcon-ros, colcon-bash; pinned in requirements-test.txt)
on this repository: colcon-ros builds an ament_python package with setuptools alone (it needs no ament_package),
so this runs without a ROS installation. `ros2 run PKG EXE` finds PKG's prefix in the ament index
(AMENT_PREFIX_PATH, set by sourcing install/setup.bash) and runs PREFIX/lib/PKG/EXE: the test does the same with
ament_index_python, which comes with rclpy.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = ('fastep_core', 'msg_tools', 'fastep_ros')
PACKAGE = 'fastep_ros'

# The rosdep key of every non-ROS module the product imports (ROS packages are their own keys).
PYTHON_KEYS = {
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'yaml': 'python3-yaml',
    'matplotlib': 'python3-matplotlib',
    'tqdm': 'python3-tqdm',
    'mcap': 'python3-mcap-pip',
    'zstandard': 'python3-zstandard',
    'lz4': 'python3-lz4',
    'rosbags': 'python3-rosbags-pip',
    'foxglove': 'python3-foxglove-sdk-pip',
    'mujoco': 'python3-mujoco-pip',
}

# Imported only for an optional extra of setup.py, so no exec_depend: a robot never needs them.
# fastep_core/experiments/cluster.py (fastep-bench / fastep-tune --cluster): the extra installs dask[distributed].
OPTIONAL = {'distributed': 'cluster', 'dask': 'cluster'}


def console_scripts() -> list[str]:
    tree = ast.parse((ROOT / 'setup.py').read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg == 'entry_points':
            return sorted(entry.split('=')[0].strip() for entry in ast.literal_eval(node.value)['console_scripts'])
    raise AssertionError('setup.py has no entry_points')


def third_party_imports() -> set[str]:
    """Top-level names of every module the product imports (anywhere in a file), less the stdlib and itself."""
    names: set[str] = set()
    for package in (*PRODUCT, 'launch'):   # launch/: the installed launch files
        for path in (ROOT / package).rglob('*.py'):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    names.update(alias.name.split('.')[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add(node.module.split('.')[0])
    return names - set(sys.stdlib_module_names) - set(PRODUCT)


def is_ros_package(name: str) -> bool:
    return (name in {'rclpy', 'tf2_ros', 'launch', 'launch_ros', 'ament_index_python'}
            or name.endswith(('_msgs', '_interfaces', '_srvs')))


def package_xml_keys(tag: str) -> set[str]:
    return {element.text or '' for element in ET.parse(ROOT / 'package.xml').getroot().iter(tag)}


def test_package_xml_exec_depends_are_exactly_the_runtime_imports() -> None:
    imports = third_party_imports() - set(OPTIONAL)
    unknown = sorted(name for name in imports if name not in PYTHON_KEYS and not is_ros_package(name))
    assert unknown == [], 'imported by the product, no rosdep key known: add it to PYTHON_KEYS and package.xml'
    needed = {PYTHON_KEYS.get(name, name) for name in imports}
    assert package_xml_keys('exec_depend') == needed


def test_rosdep_yaml_defines_the_keys_rosdistro_lacks_for_debian_and_ubuntu() -> None:
    rules = yaml.safe_load((ROOT / 'rosdep.yaml').read_text())
    assert set(rules) == {'python3-mcap-pip', 'python3-zstandard', 'python3-lz4', 'python3-rosbags-pip',
                          'python3-foxglove-sdk-pip', 'python3-mujoco-pip'}
    assert set(rules) <= package_xml_keys('exec_depend')
    assert all({'debian', 'ubuntu'} <= set(rule) for rule in rules.values())


def requirements(tmp_path: Path, **environ: str) -> dict[str, list[str]]:
    """setup.py's requirements as setuptools writes them: {'' (install_requires) or extra: lines}."""
    env = {key: value for key, value in os.environ.items() if key != 'ROS_DISTRO'} | environ
    tmp_path.mkdir()
    subprocess.run([sys.executable, 'setup.py', '-q', 'egg_info', '--egg-base', str(tmp_path)], cwd=ROOT, env=env,
                   check=True, capture_output=True, timeout=120)
    sections: dict[str, list[str]] = {'': []}
    current = ''
    for line in (tmp_path / f'{PACKAGE}.egg-info' / 'requires.txt').read_text().splitlines():
        if line.startswith('['):
            current = line.strip('[]')
            sections[current] = []
        elif line:
            sections[current].append(line)
    return sections


def ros_wheels(lines: list[str]) -> list[str]:
    return [line for line in lines if line.startswith('ros-')]


def test_pip_brings_the_ros_wheels_only_where_no_ros_is_installed(tmp_path: Path) -> None:
    """Issue 14: `pip install` into a sourced ROS installation pulled a second rclpy from the PyPI wheels."""
    fresh = requirements(tmp_path / 'fresh')
    sourced = requirements(tmp_path / 'sourced', ROS_DISTRO='jazzy')
    assert ros_wheels(fresh['']) == ['ros-jazzy-rclpy[fastrtps]==7.1.6', 'ros-jazzy-common-interfaces==5.3.6']
    assert ros_wheels(sourced['']) == []
    assert fresh['ros-wheels'] == sourced['ros-wheels'] == ros_wheels(fresh[''])
    assert [line for line in fresh[''] if not line.startswith('ros-')] == sourced['']


def test_dask_is_an_extra_that_make_test_pins(tmp_path: Path) -> None:
    """--cluster's engine is optional: the extra `cluster`, not install_requires; requirements-test.txt pins it so
    make test runs tests/fastep_core/test_cluster.py."""
    found = requirements(tmp_path / 'setup')
    assert found['cluster'] == ['dask[distributed]>=2026.1']
    assert not any(line.startswith(('dask', 'distributed')) for line in found[''])
    pinned = (ROOT / 'requirements-test.txt').read_text().splitlines()
    assert {'dask==2026.8.0', 'distributed==2026.8.0'} <= set(pinned)


def sourced(install: Path, script: str, **environ: str) -> subprocess.CompletedProcess[str]:
    """Run a bash script after `source install/setup.bash`, as a ROS user does, with none of this checkout on
    PYTHONPATH (so the product is imported from the install)."""
    env = {key: value for key, value in os.environ.items()
           if key not in ('PYTHONPATH', 'AMENT_PREFIX_PATH', 'COLCON_PREFIX_PATH')} | environ
    return subprocess.run(['bash', '-c', f'source {install}/setup.bash && {script}'], cwd=install.parent, env=env,
                          capture_output=True, text=True, timeout=300)


def build_outputs() -> list[str]:
    """What a build writing into the sources would leave in the checkout (other tests may add other files)."""
    return sorted(p.name for p in ROOT.iterdir() if p.name in ('build', 'install', 'log') or p.suffix == '.egg-info')


@pytest.fixture(scope='module')
def colcon_install(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`colcon build` of this repository into a workspace of its own; the sources stay untouched."""
    workspace = tmp_path_factory.mktemp('colcon')
    before = build_outputs()
    colcon = 'import sys; from colcon_core.command import main; sys.exit(main())'
    env = {key: value for key, value in os.environ.items() if key not in ('PYTHONPATH', 'ROS_DISTRO')}
    env['COLCON_HOME'] = str(workspace / 'colcon_home')   # no user defaults or mixins
    done = subprocess.run(
        [sys.executable, '-c', colcon, '--log-base', str(workspace / 'log'), 'build', '--paths', str(ROOT),
         '--build-base', str(workspace / 'build'), '--install-base', str(workspace / 'install'),
         '--event-handlers', 'console_direct-'],
        cwd=workspace, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert build_outputs() == before
    return workspace / 'install'


def test_colcon_build_installs_every_console_script_where_ros2_run_looks(colcon_install: Path) -> None:
    lib = colcon_install / PACKAGE / 'lib' / PACKAGE
    installed = sorted(p.name for p in lib.iterdir() if p.is_file() and os.access(p, os.X_OK))
    assert installed == console_scripts()
    assert (colcon_install / PACKAGE / 'share' / PACKAGE / 'package.xml').is_file()
    # Where `ros2 launch fastep_ros planner.launch.py` finds it (the share folder), with the params it defaults to.
    assert (colcon_install / PACKAGE / 'share' / PACKAGE / 'launch' / 'planner.launch.py').is_file()
    assert (colcon_install / PACKAGE / 'share' / PACKAGE / 'config' / 'planner.yaml').is_file()


# `ros2 run PKG EXE ARGS` (ros2run's logic, without the ros2 CLI): the prefix from the ament index, then
# PREFIX/lib/PKG/EXE, which must be an executable file.
ROS2_RUN = """
import os, subprocess, sys
from ament_index_python.packages import get_package_prefix
import msg_tools
package, executable, *args = sys.argv[1:]
path = os.path.join(get_package_prefix(package), 'lib', package, executable)
assert os.path.isfile(path) and os.access(path, os.X_OK), path
print(path)
print(msg_tools.__file__, flush=True)
sys.exit(subprocess.run([path, *args]).returncode)
"""


def test_ros2_run_finds_and_runs_the_installed_scripts(colcon_install: Path) -> None:
    """`ros2 run fastep_ros fastep-sim --list` after sourcing the install runs the installed code."""
    done = sourced(colcon_install, f'"{sys.executable}" -c "$ROS2_RUN" {PACKAGE} fastep-sim --list',
                   ROS2_RUN=ROS2_RUN)
    assert done.returncode == 0, done.stderr
    path, module, *listing = done.stdout.splitlines()
    assert Path(path) == colcon_install / PACKAGE / 'lib' / PACKAGE / 'fastep-sim'
    assert Path(module).is_relative_to(colcon_install / PACKAGE)
    assert 'case_study_1' in listing
