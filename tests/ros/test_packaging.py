"""Packaging: each package's package.xml declares what its code imports, so `rosdep install
--from-paths src` on a stock ROS install gives every node and tool what it needs; the
licence; config/ installed to share/; `colcon test` configured to run the suite.

Imports are read with `ast` from every .py of the package (module level or inside functions,
`import x` and `from x import y`; relative imports are the package's own). The top-level name
of each is the standard library, a package of this workspace, a ROS package (its name is its
rosdep key), or a Python distribution with a rosdep key below. The keys were checked against
ros/rosdistro (rosdep/python.yaml, rosdep/base.yaml, jazzy/distribution.yaml): a new import
that is none of these fails here until it is given a key (or the key's absence is stated).
The checker is tried on a synthetic package first, so a clean result means something.
"""
from __future__ import annotations

import ast
import configparser
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / 'src'
PACKAGES = sorted(p.parent.name for p in SRC.glob('*/package.xml'))

# Python import name -> rosdep key
PYTHON_KEYS = {
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'numba': 'python3-numba',
    'llvmlite': 'python3-numba',        # numba's code generator, installed with it (compiled_boxing.py)
    'yaml': 'python3-yaml',
    'matplotlib': 'python3-matplotlib',
    'tqdm': 'python3-tqdm',
    'pytest': 'python3-pytest',
    'rosbags': 'python3-rosbags-pip',
    # the `mcap` distribution has no key of its own: mcap-ros2-support (pip) requires it, and
    # mcap requires lz4 and zstandard (imported by bag.py's salvage of compressed chunks)
    'mcap_ros2': 'mcap-ros2-support',
    'mcap': 'mcap-ros2-support',
    'lz4': 'mcap-ros2-support',
    'zstandard': 'mcap-ros2-support',
    # no key in ros/rosdistro: the project's own rosdep/python.yaml defines it (README: add it to rosdep)
    'ambiance': 'python3-ambiance-pip',
    'setproctitle': 'python3-setproctitle-pip',
}
# ROS packages of Jazzy the code may import (import name = package name = rosdep key)
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'ament_index_python', 'rosidl_parser',
                'rosidl_runtime_py', 'std_msgs', 'geometry_msgs', 'sensor_msgs', 'nav_msgs', 'rosgraph_msgs',
                'diagnostic_msgs'}
# imports without a rosdep key: allowed undeclared only where every import of them is guarded
# by `except ImportError` (the feature says what to install)
NO_KEY = {'dask': 'pip install "dask[distributed]" (requirements.txt); only --scheduler uses it'}
RUN_TAGS = ('exec_depend', 'depend')


@dataclass(frozen=True)
class Use:
    """`path` imports the top-level module `name` (line `line`); `guarded`: inside a `try`
    that catches ImportError."""
    path: Path
    name: str
    line: int
    guarded: bool

    def __str__(self) -> str:
        return f'{self.path.name}:{self.line} imports {self.name}'


def _catches_import_error(handler: ast.ExceptHandler) -> bool:
    types = handler.type.elts if isinstance(handler.type, ast.Tuple) else [handler.type]
    return any(isinstance(t, ast.Name) and t.id in ('ImportError', 'ModuleNotFoundError') for t in types)


def uses_of(path: Path) -> list[Use]:
    """Every absolute import of one file, by top-level module name."""
    tree = ast.parse(path.read_text(), filename=str(path))
    guarded_nodes: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Try) and any(_catches_import_error(h) for h in node.handlers):
            guarded_nodes.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        else:
            continue
        for name in names:
            out.append(Use(path, name.split('.')[0], node.lineno, id(node) in guarded_nodes))
    return out


def python_files(pkg_dir: Path) -> list[Path]:
    """The package's Python modules (its import packages; not setup.py, not tests)."""
    return sorted(f for d in pkg_dir.iterdir() if (d / '__init__.py').is_file() for f in d.rglob('*.py'))


def declared(package_xml: Path, tags=RUN_TAGS) -> set[str]:
    root = ET.parse(package_xml).getroot()
    return {e.text.strip() for t in tags for e in root.findall(t)}


def problems(pkg_dir: Path, workspace: set[str]) -> list[str]:
    """Imports of the package at `pkg_dir` without a declared run dependency, and imports
    this checker cannot map to a rosdep key."""
    name = ET.parse(pkg_dir / 'package.xml').getroot().findtext('name')
    deps = declared(pkg_dir / 'package.xml')
    out = []
    for use in (u for f in python_files(pkg_dir) for u in uses_of(f)):
        top = use.name
        if top in sys.stdlib_module_names or top == name:
            continue
        if top in NO_KEY:
            if not use.guarded:
                out.append(f'{use}: no rosdep key ({NO_KEY[top]}); guard it with except ImportError')
            continue
        key = top if top in workspace or top in ROS_PACKAGES else PYTHON_KEYS.get(top)
        if key is None:
            out.append(f'{use}: unknown to tests/ros/test_packaging.py; add its rosdep key there')
        elif key not in deps:
            out.append(f'{use}: package.xml has no <exec_depend>{key}</exec_depend>')
    return sorted(set(out))


# --- the checker on a synthetic package ----------------------------------------------------

def _fake_package(tmp: Path, deps: list[str], modules: dict[str, str]) -> Path:
    pkg = tmp / 'fake_pkg'
    (pkg / 'fake_pkg').mkdir(parents=True)
    (pkg / 'package.xml').write_text(
        '<package format="3"><name>fake_pkg</name>'
        + ''.join(f'<exec_depend>{d}</exec_depend>' for d in deps) + '</package>')
    (pkg / 'fake_pkg' / '__init__.py').write_text('')
    for mod, text in modules.items():
        (pkg / 'fake_pkg' / mod).write_text(text)
    (pkg / 'setup.py').write_text('import setuptools\n')      # not the package's code
    return pkg


def test_checker_passes_a_fully_declared_package(tmp_path):
    pkg = _fake_package(tmp_path, ['python3-numpy', 'rclpy', 'std_msgs', 'mcap-ros2-support', 'alignment_core'], {
        'a.py': 'import os\nimport numpy as np\nfrom rclpy.node import Node\nfrom std_msgs.msg import Header\n'
                'from . import b\nfrom fake_pkg import b as c\nfrom alignment_core import units\n',
        'b.py': 'def f():\n    from mcap.reader import make_reader\n    import lz4.frame\n'
                'try:\n    import dask\nexcept ImportError:\n    dask = None\n',
    })
    assert problems(pkg, {'alignment_core', 'fake_pkg'}) == []


def test_checker_finds_missing_and_unknown_imports(tmp_path):
    pkg = _fake_package(tmp_path, ['rclpy'], {
        'a.py': 'import rclpy\ndef f():\n    from mcap.reader import make_reader\n',
        'b.py': 'from geometry_msgs.msg import Twist\nimport shapely\nimport dask\n',
        'c.py': 'from alignment_ros import topics\n',
    })
    found = problems(pkg, {'alignment_ros', 'fake_pkg'})
    assert found == [
        'a.py:3 imports mcap: package.xml has no <exec_depend>mcap-ros2-support</exec_depend>',
        'b.py:1 imports geometry_msgs: package.xml has no <exec_depend>geometry_msgs</exec_depend>',
        'b.py:2 imports shapely: unknown to tests/ros/test_packaging.py; add its rosdep key there',
        f'b.py:3 imports dask: no rosdep key ({NO_KEY["dask"]}); guard it with except ImportError',
        'c.py:1 imports alignment_ros: package.xml has no <exec_depend>alignment_ros</exec_depend>',
    ]


# --- the real packages ---------------------------------------------------------------------

@pytest.mark.parametrize('pkg', PACKAGES)
def test_every_import_has_its_dependency(pkg):
    assert python_files(SRC / pkg), pkg
    found = problems(SRC / pkg, set(PACKAGES))
    assert not found, f'{pkg}:\n  ' + '\n  '.join(found)


@pytest.mark.parametrize('pkg', PACKAGES)
def test_declared_keys_are_known_and_tests_have_pytest(pkg):
    """No typo'd or invented key: every dependency is a workspace package, a ROS package or a
    rosdep key of the table above; format 3, Apache-2.0, pytest for the tests."""
    xml = SRC / pkg / 'package.xml'
    root = ET.parse(xml).getroot()
    assert root.get('format') == '3'
    assert root.findtext('name') == pkg
    assert root.findtext('license') == 'Apache-2.0'
    known = set(PACKAGES) | ROS_PACKAGES | set(PYTHON_KEYS.values())
    every = declared(xml, ('depend', 'build_depend', 'exec_depend', 'test_depend', 'buildtool_depend'))
    assert every <= known, every - known
    assert 'python3-pytest' in declared(xml, ('test_depend',))
    assert root.find('export/build_type').text == 'ament_python'


def test_licence_is_the_apache_2_text():
    text = (ROOT / 'LICENSE').read_text()
    assert text.split('\n')[1].strip() == 'Apache License'
    assert text.split('\n')[2].strip() == 'Version 2.0, January 2004'
    assert 'TERMS AND CONDITIONS FOR USE, REPRODUCTION, AND DISTRIBUTION' in text
    assert 'END OF TERMS AND CONDITIONS' in text
    assert len(text.split()) > 1500          # the full text (about 1 580 words), not a stub
    for pkg in PACKAGES:
        assert "license='Apache-2.0'" in (SRC / pkg / 'setup.py').read_text(), pkg


# --- config/ installed ---------------------------------------------------------------------

def _installed_config() -> Path:
    return ROOT / 'ros2_ws/install/alignment_core/share/alignment_core/config'


def test_config_is_installed_to_share():
    installed = _installed_config()
    for sub in ('scenarios', 'params'):
        want = sorted(p.name for p in (ROOT / 'config' / sub).glob('*.yaml'))
        assert want, sub
        got = sorted(p.name for p in (installed / sub).glob('*.yaml'))
        assert got == want, sub
        for name in want:
            assert (installed / sub / name).read_bytes() == (ROOT / 'config' / sub / name).read_bytes()


def test_config_dir_falls_back_to_the_installed_share(monkeypatch):
    """Without ALIGN_ROOT: the source tree's config/ when the code runs from it, else (an
    install without the repository: here, the module seen at a path with no config/ above
    it) the one in share/alignment_core found through the ament index."""
    from alignment_core.config import scenario
    monkeypatch.delenv('ALIGN_ROOT', raising=False)
    assert scenario.config_dir() == ROOT / 'config'
    fake = Path('/nonexistent/lib/python3/site-packages/alignment_core/config/scenario.py')
    monkeypatch.setattr(scenario, '__file__', str(fake))
    assert os.environ.get('AMENT_PREFIX_PATH'), 'the workspace is not sourced'
    assert scenario.config_dir().resolve() == _installed_config().resolve()
    assert scenario.scenario_path('catapult').resolve() == (_installed_config() / 'scenarios/catapult.yaml').resolve()
    assert scenario.load('catapult') == scenario.load(str(ROOT / 'config/scenarios/catapult.yaml'))


# --- colcon test ---------------------------------------------------------------------------

def _pytest_section(pkg: str) -> configparser.SectionProxy:
    cfg = configparser.ConfigParser(interpolation=None)
    cfg.read(SRC / pkg / 'setup.cfg')
    assert cfg.has_section('tool:pytest'), f'{pkg}/setup.cfg: no [tool:pytest]'
    return cfg['tool:pytest']


def _setup_extras(pkg: str) -> dict:
    tree = ast.parse((SRC / pkg / 'setup.py').read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg == 'extras_require':
            return ast.literal_eval(node.value)
    return {}


def test_every_test_file_is_run_by_colcon_test():
    """colcon runs pytest in each package's directory (only when setup.py lists pytest among
    its test extras), configured by its setup.cfg [tool:pytest] as pytest.ini configures the
    suite; together the packages' test paths cover every test module of tests/."""
    suite = configparser.ConfigParser(interpolation=None)
    suite.read(ROOT / 'pytest.ini')
    covered: set[Path] = set()
    for pkg in PACKAGES:
        assert 'pytest' in _setup_extras(pkg).get('test', []), pkg
        sec = _pytest_section(pkg)
        assert (SRC / pkg / sec['pythonpath']).resolve() == (ROOT / suite['pytest']['pythonpath']).resolve()
        assert sec['filterwarnings'].split() == suite['pytest']['filterwarnings'].split()
        assert '--confcutdir=../..' in sec['addopts'].split()     # tests/conftest.py is loaded
        for rel in sec['testpaths'].split():
            path = (SRC / pkg / rel).resolve()
            assert path.exists(), f'{pkg}: {rel}'
            covered |= {path} if path.is_file() else set(path.rglob('test_*.py'))
    every = {p.resolve() for p in (ROOT / 'tests').rglob('test_*.py') if 'support' not in p.parts}
    assert every - covered == set()


def test_keys_not_in_rosdistro_are_defined_by_the_projects_rosdep_file():
    """python3-ambiance-pip and python3-setproctitle-pip are the project's own keys:
    rosdep/python.yaml must define each as a pip install of the distribution, for the platforms
    a Jazzy user runs."""
    import yaml
    own = yaml.safe_load((ROOT / 'rosdep' / 'python.yaml').read_text())
    assert own['python3-ambiance-pip']['ubuntu']['pip']['packages'] == ['ambiance']
    assert own['python3-ambiance-pip']['debian']['pip']['packages'] == ['ambiance']
    for os_name in ('ubuntu', 'debian'):
        assert own['python3-setproctitle-pip'][os_name]['pip']['packages'] == ['setproctitle']
