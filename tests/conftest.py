"""Shared test fixtures: `ros` starts project nodes as processes on a private ROS domain and
drives them from an in-process rclpy node (helpers that are not fixtures live in tests/support/)."""
from __future__ import annotations

import os
import signal
import subprocess
from pathlib import Path

import pytest

# before numpy loads: one BLAS thread, as scripts/env.sh sets it (a multithreaded BLAS moves the last bits,
# and the freshness test compares the experiments' runs.csv byte for byte with docs/results.md)
for _var in ('OMP_NUM_THREADS', 'OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS'):
    os.environ.setdefault(_var, '1')
# ... and OpenBLAS's Haswell kernels on a CPU that has their instructions, as env.sh chooses them


def _has_avx2_fma() -> bool:
    try:
        flags = Path('/proc/cpuinfo').read_text().split()
    except OSError:
        return False
    return 'avx2' in flags and 'fma' in flags


if _has_avx2_fma():
    os.environ.setdefault('OPENBLAS_CORETYPE', 'Haswell')

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / 'config/params/catapult_paper.yaml'
# the DDS profile scripts/env.sh exports (loopback only; writers wait for slow readers), also for the
# test process's own participants when pytest runs without env.sh
os.environ.setdefault('FASTRTPS_DEFAULT_PROFILES_FILE', str(ROOT / 'config/dds/fastdds.xml'))
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'SYSTEM_DEFAULT')
# every test runs on a domain of its own (claimed, or given to its processes explicitly): a
# ROS_DOMAIN_ID exported in the shell, which run_graph.sh and replay.sh honour, must not
# put the suite's runs on one shared domain
os.environ.pop('ROS_DOMAIN_ID', None)


def _param_args(sets: dict) -> list[str]:
    return [a for k, v in sets.items() for a in ('-p', f'{k}:={str(v).lower() if isinstance(v, bool) else v}')]


@pytest.fixture
def ros():
    """(driver node, start): start(name, *ros_args, sets={key: value}) launches a node with the
    default params file; every started node is stopped (SIGINT, then SIGKILL) afterwards."""
    import rclpy

    from alignment_ros import domain
    dom = domain.claim()
    rclpy.init(domain_id=dom)
    node = rclpy.create_node('test_driver')
    procs: list[subprocess.Popen] = []

    def start(name: str, *args: str, sets: dict | None = None) -> subprocess.Popen:
        p = subprocess.Popen([str(ROOT / 'scripts/start_node.sh'), name, '--params-file', str(PARAMS),
                              '--ros-args', *args, *_param_args(sets or {})],
                             env=dict(os.environ, ROS_DOMAIN_ID=str(dom)), stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, start_new_session=True)
        procs.append(p)
        return p
    yield node, start
    for p in procs:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
    node.destroy_node()
    rclpy.shutdown()
    domain.release(dom)
