"""Back-pressure stress: N graph runs as fast as possible, optionally beside K CPU-bound processes.

    scripts/bench.sh stress_rtf0 [--runs 20] [--load K] [--rtf 0] [--set KEY=VALUE ...]

At real_time_factor 0 the ship node publishes faster than its slowest reliable reader takes, so
its writers run with a full KEEP_ALL history and every publish waits for acknowledgements (Fast
DDS: up to max_blocking_time, then the write fails). This runs scripts/run_graph.sh N times and
reports the runs that failed (with the node and the first error line of its log), the messages
lost by the runs that finished (summary.json: lost_total, must be 0) and the publishes that had
to wait (the nodes' stats: publish_waits).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SETS = ['duration_s=30.0', 'aircraft.catapult.launch_time_s=25.0']
ERROR_MARKS = ('RCLError', 'cannot publish data', 'Traceback')


def start_load(k: int) -> list[subprocess.Popen]:
    """K busy-looping Python processes (the CPU-bound neighbours of a loaded machine)."""
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(k)]


def stop_load(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        p.kill()
        p.wait()


def failure_reason(out: Path, stderr: str) -> str:
    """The first error line of a node's log (node named), else the last line run_graph printed."""
    for log in sorted((out / 'logs').glob('*.log')):
        for line in log.read_text(errors='replace').splitlines():
            if any(m in line for m in ERROR_MARKS) and 'Traceback' not in line:
                return f'{log.stem}: {line.strip()[:160]}'
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    return lines[-1][:200] if lines else 'no output'


def publish_waits(out: Path) -> int:
    n = 0
    for f in (out / 'stats').glob('*_node.json'):
        n += sum(json.loads(f.read_text()).get('publish_waits', {}).values())
    return n


def one_run(out: Path, rtf: float, scenario: str, sets: list[str], timeout: float) -> dict:
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', scenario, '--out', str(out),
           '--real-time-factor', repr(rtf)]
    for s in sets:
        cmd += ['--set', s]
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        rc, stderr = p.returncode, p.stderr
    except subprocess.TimeoutExpired as e:
        rc, stderr = -1, f'timed out after {timeout:.0f} s\n{e.stderr or ""}'
    r = {'rc': rc, 'wall_s': time.monotonic() - t0, 'failed': rc != 0, 'lost_total': None,
         'publish_waits': publish_waits(out) if (out / 'stats').exists() else 0, 'reason': ''}
    summary = out / 'summary.json'
    if rc == 0 and summary.exists():
        sm = json.loads(summary.read_text())
        r['lost_total'] = sm['lost_total']
        r['estimate'] = sm.get('misalignment_estimate_rad')
        ship = out / 'stats' / 'ship_motion_node.json'
        r['pace_waits'] = json.loads(ship.read_text()).get('pace_waits', 0) if ship.exists() else 0
    else:
        r['failed'] = True
        r['reason'] = failure_reason(out, stderr) if out.exists() else stderr.strip()[-200:]
    return r


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--runs', type=int, default=20)
    ap.add_argument('--load', type=int, default=0, help='extra CPU-bound processes during the runs')
    ap.add_argument('--rtf', type=float, default=0.0, help='real_time_factor (0: as fast as possible)')
    ap.add_argument('--scenario', default='catapult_paper')
    ap.add_argument('--set', dest='sets', action='append', default=None, metavar='KEY=VALUE',
                    help=f'scenario overrides (default: {" ".join(DEFAULT_SETS)})')
    ap.add_argument('--timeout', type=float, default=900.0, help='wall seconds per run')
    ap.add_argument('--keep', type=Path, default=None, help='keep the runs under this directory')
    ap.add_argument('--json', type=Path, default=None, help='write the per-run results here')
    a = ap.parse_args()
    sets = DEFAULT_SETS if a.sets is None else a.sets
    base = a.keep or Path(tempfile.mkdtemp(prefix='stress_rtf0-'))
    load = start_load(a.load)
    results = []
    try:
        for i in range(a.runs):
            r = one_run(base / f'run{i:03d}', a.rtf, a.scenario, sets, a.timeout)
            results.append(r)
            status = (f'FAILED ({r["reason"]})' if r['failed'] else
                      f'ok, lost {r["lost_total"]}, ship lead waits {r["pace_waits"]}')
            print(f'run {i + 1}/{a.runs}: {r["wall_s"]:.1f} s, publish waits {r["publish_waits"]}, '
                  f'{status}', flush=True)
    finally:
        stop_load(load)
        if a.keep is None:
            subprocess.run(['rm', '-rf', str(base)], check=False)
    failed = sum(r['failed'] for r in results)
    lost = sum(r['lost_total'] or 0 for r in results)
    print(f'rtf {a.rtf:g}, load {a.load}, {" ".join(sets)}: {failed} of {len(results)} runs failed, '
          f'{lost} messages lost in the {len(results) - failed} that finished, '
          f'{sum(r["publish_waits"] for r in results)} publishes waited; '
          f'{len({json.dumps(r.get("estimate")) for r in results if not r["failed"]})} distinct final estimate(s) '
          'among them (the same scenario and seed: 1)')
    if a.json:
        a.json.write_text(json.dumps(results, indent=1))
    return 1 if failed or lost else 0


if __name__ == '__main__':
    sys.exit(main())
