"""The core's architecture, read from its source with `ast` (every import statement, at module
level or inside functions, absolute or relative):

- layering: geometry, navigation and estimation never import the simulator (ship, aircraft,
  sensors, config, pipeline, run_out, evaluation); nor do the foundation modules (units, validation,
  gauss_markov, rng, samples); geometry imports neither navigation nor estimation, navigation
  not estimation; recorded (logs in) neither the simulator nor navigation and estimation;
  air_data (atmosphere, pitot, ports, FADS solve: shared by the simulator and the estimator,
  so geometry, navigation and estimation may import it) imports only units,
  validation and geometry of the package, and numpy, scipy, ambiance and the standard library;
- no import cycle among alignment_core's modules (a package's __init__ is a module);
- alignment_core never imports rclpy, ROS message packages or the ROS glue.

The checker is tested on synthetic trees first, so a clean result on the real tree means
something: it finds a violation, a cycle and a ROS import where there is one.
"""
from __future__ import annotations

import ast
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

CORE = Path(__file__).resolve().parents[1] / 'src/alignment_core/alignment_core'
PACKAGE = 'alignment_core'

SIMULATOR = ('ship', 'aircraft', 'sensors', 'config', 'pipeline', 'run_out', 'evaluation')
FOUNDATION = ('units', 'validation', 'gauss_markov', 'rng', 'samples')
# first component under alignment_core -> the components it must never import
FORBIDDEN: dict[str, tuple[str, ...]] = {
    'geometry': SIMULATOR + ('navigation', 'estimation'),
    'navigation': SIMULATOR + ('estimation',),
    'estimation': SIMULATOR,
    'air_data': SIMULATOR + ('navigation', 'estimation', 'gauss_markov', 'rng', 'samples'),
    'recorded': SIMULATOR + ('navigation', 'estimation'),     # recorded logs in: no simulator
    **{name: SIMULATOR for name in FOUNDATION},
}
AIR_DATA_MAY_IMPORT = ('air_data', 'units', 'validation', 'geometry')
AIR_DATA_THIRD_PARTY = ('numpy', 'scipy', 'ambiance')
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'rosidl_runtime_py', 'rosbag2_py', 'launch',
                'launch_ros', 'message_filters', 'tf2_ros', 'alignment_ros'}
ROS_SUFFIXES = ('_msgs', '_srvs', '_interfaces', '_node')


@dataclass(frozen=True)
class Import:
    """`module` (dotted) imports `target`: for a module of the package, the module file the
    statement resolves to (a package's __init__ is the package's own name)."""
    module: str
    target: str
    line: int

    def __str__(self) -> str:
        return f'{self.module} imports {self.target} (line {self.line})'


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Dotted module name -> file, for every .py under `root` (the package directory)."""
    out = {}
    for path in sorted(root.rglob('*.py')):
        parts = [package, *path.relative_to(root).with_suffix('').parts]
        if parts[-1] == '__init__':
            parts.pop()
        out['.'.join(parts)] = path
    return out


def _in_package(name: str, modules: dict[str, Path]) -> str:
    """The longest prefix of `name` that is a module of the package ('' if none)."""
    parts = name.split('.')
    for n in range(len(parts), 0, -1):
        cand = '.'.join(parts[:n])
        if cand in modules:
            return cand
    return ''


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> list[Import]:
    """Every import statement of one module, anywhere in its tree (module level, functions,
    classes, conditionals). Package-internal targets resolve to a module of `modules`;
    anything else keeps its dotted name."""
    is_pkg = path.name == '__init__.py'
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split('.') if is_pkg else name.split('.')[:-1]
                base = base[:len(base) - (node.level - 1)]
                stem = '.'.join(base + ([node.module] if node.module else []))
            else:
                stem = node.module or ''
            # `from p import m`: m is a submodule (a dependency on m) or a name defined in p
            names = [f'{stem}.{a.name}' if f'{stem}.{a.name}' in modules else stem for a in node.names]
        else:
            continue
        for target in dict.fromkeys(names):
            out.append(Import(name, _in_package(target, modules) or target, node.lineno))
    return out


def all_imports(root: Path, package: str) -> tuple[dict[str, Path], list[Import]]:
    modules = module_files(root, package)
    return modules, [i for name, path in modules.items() for i in imports_of(name, path, modules)]


def _component(module: str, package: str) -> str:
    """First component under the package ('' for the package's own __init__)."""
    parts = module.split('.')
    return parts[1] if len(parts) > 1 and parts[0] == package else ''


def layering_violations(imports: list[Import], package: str,
                        forbidden: dict[str, tuple[str, ...]] = FORBIDDEN) -> list[Import]:
    return [i for i in imports
            if i.target.split('.')[0] == package
            and _component(i.target, package) in forbidden.get(_component(i.module, package), ())]


def ros_imports(imports: list[Import]) -> list[Import]:
    def is_ros(top: str) -> bool:
        return top in ROS_PACKAGES or top.endswith(ROS_SUFFIXES)
    return [i for i in imports if is_ros(i.target.split('.')[0])]


def import_cycles(modules: dict[str, Path], imports: list[Import]) -> list[list[Import]]:
    """Tarjan's strongly connected components of the package's module graph; for each
    component with a cycle, the imports that close it (edges inside the component)."""
    graph: dict[str, list[Import]] = {m: [] for m in modules}
    for i in imports:
        if i.target in graph:
            graph[i.module].append(i)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[Import]] = []

    def visit(v: str) -> None:      # recursion depth is bounded by the number of modules (~80)
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for e in graph[v]:
            if e.target not in index:
                visit(e.target)
                low[v] = min(low[v], low[e.target])
            elif e.target in on_stack:
                low[v] = min(low[v], index[e.target])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            edges = [e for m in sorted(comp) for e in graph[m] if e.target in comp]
            if edges:                 # more than one module, or a module importing itself
                cycles.append(edges)

    for m in sorted(graph):
        if m not in index:
            visit(m)
    return cycles


def _report(title: str, items) -> str:
    return title + ':\n  ' + '\n  '.join(str(i) for i in items)


# --- the real tree ----------------------------------------------------------------------

def test_the_checker_reads_the_real_tree():
    """Guard against a checker that silently sees nothing: the tree has its subpackages, and
    imports inside functions and `from package import module` forms resolve to the module."""
    modules, imports = all_imports(CORE, PACKAGE)
    assert {'alignment_core', 'alignment_core.geometry', 'alignment_core.estimation.models',
            'alignment_core.ship.manoeuvring.mmg', 'alignment_core.pipeline'} <= set(modules)
    edges = {(i.module, i.target) for i in imports}
    # function-level: PaperShipMotion._box_waves imports sea_state and mmg when it needs them
    assert ('alignment_core.ship.paper', 'alignment_core.ship.sea_state') in edges
    assert ('alignment_core.ship.paper', 'alignment_core.ship.manoeuvring.mmg') in edges
    assert len(imports) > 200


def test_layering():
    _, imports = all_imports(CORE, PACKAGE)
    bad = layering_violations(imports, PACKAGE)
    assert not bad, _report('layering violations (see FORBIDDEN)', bad)


def air_data_violations(imports: list[Import], package: str) -> list[Import]:
    """Imports of air_data outside AIR_DATA_MAY_IMPORT, the standard library and AIR_DATA_THIRD_PARTY."""
    def allowed(i: Import) -> bool:
        top = i.target.split('.')[0]
        if top == package:
            return _component(i.target, package) in AIR_DATA_MAY_IMPORT
        return top in sys.stdlib_module_names or top in AIR_DATA_THIRD_PARTY
    return [i for i in imports if _component(i.module, package) == 'air_data' and not allowed(i)]


def test_air_data_imports_only_its_layer_and_its_libraries():
    _, imports = all_imports(CORE, PACKAGE)
    assert len([i for i in imports if _component(i.module, PACKAGE) == 'air_data']) > 10
    bad = air_data_violations(imports, PACKAGE)
    assert not bad, _report('air_data imports outside its layer', bad)


def test_no_import_cycle():
    modules, imports = all_imports(CORE, PACKAGE)
    cycles = import_cycles(modules, imports)
    assert not cycles, '\n'.join(_report('import cycle', c) for c in cycles)


def test_no_ros_in_the_core():
    _, imports = all_imports(CORE, PACKAGE)
    bad = ros_imports(imports)
    assert not bad, _report('ROS imports in alignment_core (it must run without ROS)', bad)


# --- the checker on synthetic trees ----------------------------------------------------

def _tree(root: Path, files: dict[str, str]) -> Path:
    pkg = root / 'pkg'
    for rel, text in files.items():
        path = pkg / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    for d in [pkg, *(p for p in pkg.rglob('*') if p.is_dir())]:
        (d / '__init__.py').touch()
    return pkg


CLEAN = {
    'units.py': 'DEG = 1.0\n',
    'geometry/earth.py': 'import math\nfrom pkg.units import DEG\n',
    'navigation/strapdown.py': 'from pkg.geometry import earth\nfrom ..units import DEG\n',
    'estimation/engine.py': 'from pkg.navigation.strapdown import x\n\ndef f():\n    from . import models\n',
    'estimation/models.py': 'import numpy as np\n',
    'ship/motion.py': 'from pkg.geometry.earth import g\nfrom pkg.estimation import engine\n',
    'pipeline.py': 'from pkg.ship import motion\nimport pkg.estimation.engine\n',
}


def test_checker_passes_a_clean_tree(tmp_path):
    modules, imports = all_imports(_tree(tmp_path, CLEAN), 'pkg')
    assert layering_violations(imports, 'pkg') == []
    assert import_cycles(modules, imports) == []
    assert ros_imports(imports) == []
    edges = {(i.module, i.target) for i in imports}
    assert ('pkg.navigation.strapdown', 'pkg.units') in edges             # relative, two dots
    assert ('pkg.estimation.engine', 'pkg.estimation.models') in edges    # relative, in a function
    assert ('pkg.pipeline', 'pkg.estimation.engine') in edges             # import a.b.c


def test_checker_finds_layering_violations(tmp_path):
    files = dict(CLEAN)
    files['geometry/earth.py'] += 'def g():\n    from ..ship import motion\n'        # relative, in a function
    files['navigation/strapdown.py'] += 'import pkg.estimation.models\n'
    files['estimation/models.py'] += 'from pkg import pipeline\n'
    files['units.py'] += 'def f():\n    from pkg.config.scenario import load\n'
    files['config/scenario.py'] = 'load = None\n'
    _, imports = all_imports(_tree(tmp_path, files), 'pkg')
    bad = {(i.module, i.target) for i in layering_violations(imports, 'pkg')}
    assert bad == {('pkg.geometry.earth', 'pkg.ship.motion'),
                   ('pkg.navigation.strapdown', 'pkg.estimation.models'),
                   ('pkg.estimation.models', 'pkg.pipeline'),
                   ('pkg.units', 'pkg.config.scenario')}
    msg = _report('layering violations', layering_violations(imports, 'pkg'))
    assert 'pkg.geometry.earth imports pkg.ship.motion (line 4)' in msg


def test_checker_finds_air_data_imports_outside_its_layer(tmp_path):
    files = dict(CLEAN)
    files['air_data/ports.py'] = ('import math\nimport numpy as np\nfrom pkg.geometry.earth import g\n'
                                  'import matplotlib\n\ndef f():\n    from pkg.navigation import strapdown\n')
    _, imports = all_imports(_tree(tmp_path, files), 'pkg')
    assert {(i.module, i.target) for i in air_data_violations(imports, 'pkg')} == {
        ('pkg.air_data.ports', 'matplotlib'), ('pkg.air_data.ports', 'pkg.navigation.strapdown')}


def test_checker_finds_cycles_through_functions_and_package_inits(tmp_path):
    files = dict(CLEAN)
    # a cycle closed by a function-level import
    files['estimation/models.py'] += 'def f():\n    from pkg.estimation.engine import run\n'
    # a package __init__ importing its submodule, which imports a name defined in the __init__
    files['ship/__init__.py'] = 'from pkg.ship.motion import Motion\n'
    files['ship/motion.py'] += 'from pkg.ship import DEFAULTS\n'
    pkg = _tree(tmp_path, files)
    modules, imports = all_imports(pkg, 'pkg')
    cycles = [{i.module for i in c} for c in import_cycles(modules, imports)]
    assert sorted(cycles, key=sorted) == [{'pkg.estimation.engine', 'pkg.estimation.models'},
                                          {'pkg.ship', 'pkg.ship.motion'}]
    # a package importing its own submodule with `from pkg.ship import motion` is no cycle by
    # itself: the edge goes to the submodule, not back to the __init__
    files['ship/motion.py'] = 'X = 1\n'
    files['estimation/models.py'] = 'import numpy as np\n'
    modules, imports = all_imports(_tree(tmp_path / 'b', files), 'pkg')
    assert import_cycles(modules, imports) == []


def test_checker_finds_ros_imports(tmp_path):
    files = dict(CLEAN)
    files['estimation/models.py'] += 'def f():\n    import rclpy\n'
    files['ship/motion.py'] += 'from geometry_msgs.msg import Pose\nfrom alignment_ros import convert\n'
    _, imports = all_imports(_tree(tmp_path, files), 'pkg')
    assert {(i.module, i.target) for i in ros_imports(imports)} == {
        ('pkg.estimation.models', 'rclpy'), ('pkg.ship.motion', 'geometry_msgs.msg'),
        ('pkg.ship.motion', 'alignment_ros')}


def test_the_alignment_pipeline_does_not_load_the_atmosphere():
    # a scenario names the day's offsets and the port layout (air_data/day_offsets.py,
    # port_layout.py); the atmosphere (ambiance, scipy.optimize) and the PCHIP table
    # (scipy.interpolate) load only where air data is simulated or estimated
    probe = ('import sys, alignment_core.pipeline, alignment_core.config.scenario as s; s.load("deck").validate(); '
             'print(sorted(m for m in ("ambiance", "scipy.optimize", "scipy.interpolate", '
             '"alignment_core.air_data.atmosphere") if m in sys.modules))')
    out = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == '[]'
