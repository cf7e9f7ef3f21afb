"""Memory soak: one long graph run of the deck scenario; every node's resident set size sampled
while it runs and its slope fitted against simulated time (target: < 1 MiB per simulated hour).

    scripts/bench.sh soak_memory [--scenario deck] [--duration-s 3600] [--rtf 5] [--every-s 5] [--set KEY=VALUE ...]
    scripts/bench.sh soak_memory --analyse SOAK.json     (the slopes of a saved run's samples)

Simulated time is read from the run's /clock (a best-effort subscriber of depth 1 on the run's
domain: it holds nothing back). The slopes are fitted over the second half of the simulated run
(the first half holds the start-up: imports, DDS discovery, the first allocations, the bag's
reorder buffer filling up to the streams' lag): through every sample, through 5-minute medians
and through 5-minute minima (see `fits`). A second table splits the resident set: its private
anonymous part (RssAnon, what a leak raises) fitted the same way, and its shared-memory part
(RssShmem: the Fast DDS segments' pages the process has touched) against the segments' mapped
size, which bounds it."""
from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NODES = ('ship_motion_node', 'master_ins_node', 'slave_ins_node', 'ldv_node', 'alignment_filter_node', 'recorder')


def descendants(root: int) -> set[int]:
    """The processes below `root` (from /proc: parent ids)."""
    parent: dict[int, int] = {}
    for proc in Path('/proc').iterdir():
        if proc.name.isdigit():
            try:
                parent[int(proc.name)] = int((proc / 'stat').read_text().rsplit(')', 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
    out: set[int] = set()
    frontier = {root}
    while frontier:
        frontier = {pid for pid, pp in parent.items() if pp in frontier} - out
        out |= frontier
    return out


# /proc/PID/status fields sampled beside VmRSS (the key NAME is VmRSS; NAME + suffix the others)
PARTS = {'RssAnon:': ' anon', 'RssShmem:': ' shmem'}
SHM_MAPPED = ' shm mapped'


def shm_mapped_mib(pid: int) -> float:
    """MiB of Fast DDS shared-memory segments and ports the process maps: the bound of its
    RssShmem (a segment's pages count once touched, and its allocator touches more of them as
    buffers land at new offsets, up to the whole segment)."""
    total = 0
    for line in (Path('/proc') / str(pid) / 'maps').read_text().splitlines():
        if '/dev/shm/fastrtps' in line:
            lo, hi = line.split(None, 1)[0].split('-')
            total += int(hi, 16) - int(lo, 16)
    return total / 2**20


def rss_by_node(root: int) -> dict[str, float]:
    """MiB resident per node process of the run below `root` (by its command line; not the
    processes of other runs on the machine): NAME is VmRSS; NAME + ' anon' its private
    anonymous part (RssAnon: what a leak raises), NAME + ' shmem' its shared-memory part and
    NAME + ' shm mapped' that part's bound (see shm_mapped_mib)."""
    out: dict[str, float] = {}
    for pid in descendants(root):
        proc = Path('/proc') / str(pid)
        try:
            argv = (proc / 'cmdline').read_bytes().decode(errors='replace').split('\0')
            status = (proc / 'status').read_text()
            shm = shm_mapped_mib(pid)
        except OSError:
            continue
        # the interpreter running a node's entry point (.../lib/NAME/NAME): not its start_node.sh,
        # nor another node whose arguments name it (hold_until_matched lists its readers)
        exe = Path(argv[1]).name if len(argv) > 1 and 'python' in Path(argv[0]).name else ''
        name = exe if exe in NODES else None
        if name is None:
            continue
        fields = {f: int(line.split()[1]) / 1024.0 for line in status.splitlines()
                  for f in ('VmRSS:', *PARTS) if line.startswith(f)}
        if 'VmRSS:' not in fields or fields['VmRSS:'] < out.get(name, 0.0):
            continue                     # the larger of a node's processes (the interpreter, not its shell)
        out[name] = fields['VmRSS:']
        out.update({name + suffix: fields[f] for f, suffix in PARTS.items() if f in fields})
        out[name + SHM_MAPPED] = shm
    return out


def clock_reader(domain: int):
    """(spin, latest): a node on the run's domain whose spin(timeout) takes /clock messages and
    latest() returns the simulated seconds of the newest (None before the first)."""
    import rclpy
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    rclpy.init(domain_id=domain)
    node = rclpy.create_node('soak_memory_clock')
    now: list[float] = []
    node.create_subscription(Clock, '/clock', lambda m: now.append(m.clock.sec + 1e-9 * m.clock.nanosec),
                             QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                                        reliability=ReliabilityPolicy.BEST_EFFORT))
    return (lambda timeout: rclpy.spin_once(node, timeout_sec=timeout)), (lambda: now[-1] if now else None)


WINDOW_S = 300.0


def fits(t: np.ndarray, r: np.ndarray) -> tuple[float, float, float]:
    """MiB per simulated hour over the second half of the run (samples taken before the
    simulation's end only): the fit through every sample; through the median of each 300 s
    window (a node whose buffers fill and drain, the recorder's reorder buffer and its trims,
    saws up and down by megabytes); and through each window's minimum, the floor a leak raises
    (the ship's transient block arrays and the sawtooth's peaks left out)."""
    half = t >= t[0] + (t[-1] - t[0]) / 2
    th, rh = t[half], r[half]
    every = float(np.polyfit(th, rh, 1)[0] * 3600.0)
    win = np.floor(th / WINDOW_S)
    keys = np.unique(win)
    if len(keys) < 3:
        return every, float('nan'), float('nan')
    tw = np.array([th[win == k].mean() for k in keys])
    med = np.array([np.median(rh[win == k]) for k in keys])
    low = np.array([rh[win == k].min() for k in keys])
    return every, float(np.polyfit(tw, med, 1)[0] * 3600.0), float(np.polyfit(tw, low, 1)[0] * 3600.0)


def report(samples: list) -> dict[str, dict[str, float]]:
    """Print and return each node's start and end RSS and its three slopes (see fits)."""
    end = max((sim for _, sim, _ in samples), default=0.0)
    print(f"{'node':<24}{'RSS start MiB':>14}{'RSS end MiB':>12}{'slope MiB/h (sim)':>19}"
          f"{'5-min medians':>15}{'5-min floors':>14}")
    out: dict[str, dict[str, float]] = {'slopes_mib_per_h': {}, 'median_slopes_mib_per_h': {},
                                        'floor_slopes_mib_per_h': {}}
    for n in NODES:
        pts = [(sim, s[n]) for _, sim, s in samples if n in s and sim < end]
        if len(pts) < 4:
            continue
        t, r = np.array(pts).T
        every, med, low = fits(t, r)
        out['slopes_mib_per_h'][n], out['median_slopes_mib_per_h'][n], out['floor_slopes_mib_per_h'][n] = \
            every, med, low
        print(f'{n:<24}{r[0]:>14.1f}{r[-1]:>12.1f}{every:>19.2f}{med:>15.2f}{low:>14.2f}')
    parts = [n for n in NODES if any(n + PARTS['RssAnon:'] in s for _, _, s in samples)]
    if not parts:
        return out          # samples saved before the parts were sampled
    print(f"\n{'node':<24}{'anon start':>11}{'anon end':>9}{'anon MiB/h':>11}{'medians':>8}{'floors':>8}"
          f"{'shmem start':>12}{'shmem end':>10}{'shm mapped':>11}")
    for k in ('anon_slopes_mib_per_h', 'anon_median_slopes_mib_per_h', 'anon_floor_slopes_mib_per_h'):
        out[k] = {}
    out['shmem_end_mib'], out['shm_mapped_mib'] = {}, {}
    for n in parts:
        pts = [(sim, s[n + ' anon'], s.get(n + ' shmem', 0.0), s.get(n + SHM_MAPPED, 0.0))
               for _, sim, s in samples if n + ' anon' in s and sim < end]
        if len(pts) < 4:
            continue
        t, anon, shmem, mapped = np.array(pts).T
        every, med, low = fits(t, anon)
        out['anon_slopes_mib_per_h'][n], out['anon_median_slopes_mib_per_h'][n] = every, med
        out['anon_floor_slopes_mib_per_h'][n] = low
        out['shmem_end_mib'][n], out['shm_mapped_mib'][n] = float(shmem[-1]), float(mapped.max())
        print(f'{n:<24}{anon[0]:>11.1f}{anon[-1]:>9.1f}{every:>11.2f}{med:>8.2f}{low:>8.2f}'
              f'{shmem[0]:>12.2f}{shmem[-1]:>10.2f}{mapped.max():>11.2f}')
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--scenario', default='deck')
    ap.add_argument('--duration-s', type=float, default=3600.0)
    ap.add_argument('--rtf', type=float, default=5.0)
    ap.add_argument('--every-s', type=float, default=5.0)
    ap.add_argument('--set', dest='sets', action='append', default=[])
    ap.add_argument('--keep', type=Path, default=None, help='run directory (default: a temporary one)')
    ap.add_argument('--json', type=Path, default=None, help='write the samples and slopes here')
    ap.add_argument('--progress', action='store_true', help='print each sample (JSON) as it is taken')
    ap.add_argument('--analyse', type=Path, default=None, metavar='JSON',
                    help="no run: print the slopes of a --json file's samples")
    a = ap.parse_args()
    if a.analyse is not None:
        report(json.loads(a.analyse.read_text())['samples'])
        return 0
    out = a.keep or Path(tempfile.mkdtemp(prefix='soak-')) / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', a.scenario, '--out', str(out),
           '--real-time-factor', str(a.rtf), '--set', f'duration_s={a.duration_s}']
    for s in a.sets:
        cmd += ['--set', s]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.stdout is not None
    first = p.stdout.readline()
    while first.startswith('setup.sh:'):
        first = p.stdout.readline()
    if not first.startswith('ROS_DOMAIN_ID='):
        print(first + p.stdout.read())
        return 1
    lines: list[str] = [first]
    threading.Thread(target=lambda: lines.extend(p.stdout), daemon=True).start()   # type: ignore[arg-type]
    spin, sim_now = clock_reader(int(first.split()[0].split('=')[1]))
    samples: list[tuple[float, float, dict[str, float]]] = []   # (wall s, simulated s, RSS MiB)
    t0 = time.monotonic()
    next_sample = t0
    while p.poll() is None:
        spin(0.05)
        now = time.monotonic()
        if now >= next_sample and sim_now() is not None:
            samples.append((now - t0, sim_now(), rss_by_node(p.pid)))   # type: ignore[arg-type]
            next_sample = now + a.every_s
            if a.progress:
                print(json.dumps(samples[-1]), flush=True)
    log = ''.join(lines)
    summary = json.loads((out / 'summary.json').read_text()) if (out / 'summary.json').exists() else {}
    rec = out / 'stats' / 'recorder.json'
    reorder = json.loads(rec.read_text()).get('reorder') if rec.exists() else None
    print(f'run exit {p.returncode}, lost {summary.get("lost_total")}, complete {summary.get("complete")}, '
          f'real-time factor {summary.get("real_time_factor") or 0:.2f}, {len(samples)} samples '
          f'over {samples[-1][1] if samples else 0:.0f} simulated s; bag reorder buffer {reorder}; '
          f'output {out}')
    if p.returncode != 0:
        print(log[-2000:])
    fits = report(samples)
    if a.json:
        a.json.write_text(json.dumps({**fits, 'summary_complete': summary.get('complete'),
                                      'lost_total': summary.get('lost_total'), 'reorder': reorder,
                                      'samples': samples}, indent=1))
    return 0 if p.returncode == 0 else 1


if __name__ == '__main__':
    raise SystemExit(main())
