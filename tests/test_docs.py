"""The documentation holds together: every link of the README and docs/ leads to a file of the repository, and no
file of the repository refers to anything outside it (a contract cited from elsewhere is a contract a reader
cannot read)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]
LINK = re.compile(r'\]\(([^)\s]+)\)')


@pytest.mark.parametrize('page', PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_every_link_leads_to_a_file_of_the_repository(page: Path) -> None:
    broken = []
    for target in LINK.findall(page.read_text()):
        if re.match(r'[a-z]+:', target) or target.startswith('#'):
            continue   # a web address or an anchor of the page itself
        path = (page.parent / target.split('#')[0]).resolve()
        if not path.exists() or ROOT not in path.parents:
            broken.append(target)
    assert not broken, f'{page.name}: links to nothing in the repository: {broken}'


def test_the_readme_is_a_front_door() -> None:
    """Issue "Front door", item 1: at most 150 lines, with the sections a newcomer looks for."""
    text = (ROOT / 'README.md').read_text()
    assert len(text.splitlines()) <= 150
    for section in ('## Two commands', '## Run your own world', '## On your robot', '## Which planner', '## Results',
                    '## As a library', '## Documentation'):
        assert section in text, section


def test_no_file_refers_outside_the_repository() -> None:
    files = subprocess.run(['git', 'ls-files'], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    outside = re.compile(r'DESIGN\.md|NOTES\.md|\.\./shared|shared/reference')
    found = [name for name in files if name.endswith(('.py', '.md', '.txt', '.cfg', '.toml', '.yaml', '.xml'))
             and name != 'tests/test_docs.py' and outside.search((ROOT / name).read_text(errors='replace'))]
    assert not found, found


def test_the_documentation_site_builds_with_every_warning_an_error(tmp_path: Path) -> None:
    """mkdocs.yml: every page of the navigation, the Python API from docstrings (mkdocstrings)."""
    import sys
    done = subprocess.run([sys.executable, '-m', 'mkdocs', 'build', '--strict', '--site-dir', str(tmp_path / 'site')],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    api = (tmp_path / 'site' / 'reference' / 'api' / 'index.html').read_text()
    assert 'load_scenario' in api and 'simulate' in api
