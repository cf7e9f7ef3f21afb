"""Memory soak: one long graph run of the deck scenario; every node's resident set size sampled
while it runs and its slope fitted against simulated time (target: < 1 MiB per simulated hour).

    scripts/bench.sh soak_memory [--duration-s 3600] [--rtf 5] [--every-s 5] [--set KEY=VALUE ...]

The slope is fitted over the second half of the run (the first half holds the start-up: imports,
DDS discovery, the first allocations). Simulated time is read from wall time and the run's own
real-time factor (summary.json)."""
from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NODES = ('ship_motion_node', 'master_ins_node', 'slave_ins_node', 'ldv_node', 'alignment_filter_node', 'recorder')


def rss_by_node() -> dict[str, float]:
    """MiB resident per node process of this machine (by its command line)."""
    out: dict[str, float] = {}
    for proc in Path('/proc').iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmd = (proc / 'cmdline').read_bytes().replace(b'\0', b' ').decode(errors='replace')
            status = (proc / 'status').read_text()
        except OSError:
            continue
        name = next((n for n in NODES if n in cmd and 'start_node.sh' not in cmd), None)
        if name is None or 'python' not in cmd and name != 'recorder':
            continue
        for line in status.splitlines():
            if line.startswith('VmRSS:'):
                out[name] = max(out.get(name, 0.0), int(line.split()[1]) / 1024.0)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--duration-s', type=float, default=3600.0)
    ap.add_argument('--rtf', type=float, default=5.0)
    ap.add_argument('--every-s', type=float, default=5.0)
    ap.add_argument('--set', dest='sets', action='append', default=[])
    a = ap.parse_args()
    out = Path(tempfile.mkdtemp(prefix='soak-')) / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'deck', '--out', str(out),
           '--real-time-factor', str(a.rtf), '--set', f'duration_s={a.duration_s}']
    for s in a.sets:
        cmd += ['--set', s]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    t0 = time.monotonic()
    samples: list[tuple[float, dict[str, float]]] = []
    while p.poll() is None:
        samples.append((time.monotonic() - t0, rss_by_node()))
        time.sleep(a.every_s)
    log = p.stdout.read() if p.stdout else ''
    summary = json.loads((out / 'summary.json').read_text()) if (out / 'summary.json').exists() else {}
    rtf = summary.get('real_time_factor') or a.rtf
    print(f'run exit {p.returncode}, lost {summary.get("lost_total")}, complete {summary.get("complete")}, '
          f'real-time factor {rtf:.2f}, {len(samples)} samples; output {out}')
    if p.returncode != 0:
        print(log[-2000:])
    print(f"{'node':<24}{'RSS start MiB':>14}{'RSS end MiB':>12}{'slope MiB/h (sim)':>19}")
    for n in NODES:
        pts = [(t * rtf, s[n]) for t, s in samples if n in s]
        if len(pts) < 4:
            continue
        t, r = np.array(pts).T
        half = t >= t[-1] / 2
        slope = np.polyfit(t[half], r[half], 1)[0] * 3600.0
        print(f'{n:<24}{r[0]:>14.1f}{r[-1]:>12.1f}{slope:>19.2f}')
    return 0 if p.returncode == 0 else 1


if __name__ == '__main__':
    raise SystemExit(main())
