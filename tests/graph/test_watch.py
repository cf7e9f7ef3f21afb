"""A run you can watch and look at, through the graph (few, short runs): run_graph.sh on a
pseudo-terminal draws one updating progress line whose final state is the run's simulated
time; a replay of that run's bag with its /truth topics removed prints plain progress lines
(its stderr is a pipe) ending at the replay's simulated time; an air-data run. Each leaves
non-empty PNGs and a report.md whose table is summary.json's; plot_bag.sh draws any bag."""
from __future__ import annotations

import fcntl
import json
import os
import pty
import re
import struct
import subprocess
import termios
import threading
from pathlib import Path

import numpy as np
import pytest
from support.bags import copy_without

from alignment_ros.state_layout import ARCMIN_PER_RAD
from alignment_ros.summary import estimates_from_bag

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=14.0', 'aircraft.catapult.launch_time_s=9.0', 'seed=3']
PNG_MAGIC = b'\x89PNG\r\n\x1a\n'
LINE = re.compile(r't = (\d+\.\d\d) / (\d+\.\d\d) s')
AXES = ('x (roll)', 'y (pitch)', 'z (yaw)')


def _on_pty(cmd: list[str], timeout: float = 400.0) -> tuple[subprocess.CompletedProcess, str]:
    """Run cmd with its stderr on a pseudo-terminal (160 columns), stdout on a pipe."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack('HHHH', 24, 160, 0, 0))
    chunks: list[bytes] = []

    def drain() -> None:                         # a full pty would block the launcher
        while True:
            try:
                b = os.read(master, 65536)
            except OSError:
                return
            if not b:
                return
            chunks.append(b)
    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=slave, text=True)
    os.close(slave)
    out, _ = p.communicate(timeout=timeout)
    reader.join(timeout=10)
    os.close(master)
    return subprocess.CompletedProcess(cmd, p.returncode, out, ''), b''.join(chunks).decode(errors='replace')


@pytest.fixture(scope='module')
def tty_run(tmp_path_factory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp('watch') / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(out)]
    for s in SETS:
        cmd += ['--set', s]
    p, tty = _on_pty(cmd)
    assert p.returncode == 0, p.stdout + tty[-3000:]
    return out, tty


@pytest.fixture(scope='module')
def truthless_replay(tty_run, tmp_path_factory) -> tuple[Path, Path, subprocess.CompletedProcess]:
    run, _ = tty_run
    base = tmp_path_factory.mktemp('truthless')
    bag = base / 'log' / 'bag'
    counts = copy_without(run / 'bag', bag)
    assert counts and not [t for t in counts if t.startswith('/truth')]
    out = base / 'replay'
    p = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(bag), '--params-file', str(run / 'params.yaml'),
                        '--out', str(out)], capture_output=True, text=True, timeout=400)
    return bag, out, p


def _pngs(d: Path) -> dict[str, int]:
    out = {}
    for p in sorted(d.glob('*.png')):
        data = p.read_bytes()
        assert data.startswith(PNG_MAGIC), p
        out[p.name] = len(data)
    return out


def _report_rows(text: str) -> dict[str, list[str]]:
    """The result table's rows: axis -> its cells."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip('|').split('|')]
        if cells and cells[0] in AXES and len(cells) == 5:
            rows[cells[0]] = cells[1:]
    return rows


def test_progress_on_a_terminal_ends_at_the_runs_sim_time(tty_run):
    run, tty = tty_run
    s = json.loads((run / 'summary.json').read_text())
    lines = [x for x in tty.replace('\r\n', '\n').split('\n') if 'run_graph:' in x and LINE.search(x)]
    assert len(lines) == 1, tty[-2000:]          # one line, redrawn in place with carriage returns
    frames = [f for f in lines[0].split('\r') if LINE.search(f)]
    assert len(frames) >= 3
    final = frames[-1]
    t, total = (float(x) for x in LINE.search(final).groups())
    assert t == pytest.approx(s['sim_time_s'], abs=0.005) and total == pytest.approx(14.0)
    assert '100%' in final and 'msgs' in final and 'misalignment' in final and 'arcmin' in final


def test_run_leaves_plots_and_a_report_matching_its_summary(tty_run):
    run, _ = tty_run
    s = json.loads((run / 'summary.json').read_text())
    sizes = _pngs(run / 'plots')
    assert set(sizes) == {'misalignment.png', 'states.png', 'consistency.png', 'motion.png'}
    assert min(sizes.values()) > 20_000
    text = (run / 'report.md').read_text()
    rows = _report_rows(text)
    assert list(rows) == list(AXES)
    for k, axis in enumerate(AXES):
        truth, est, err, sig = (float(x) for x in rows[axis])
        assert truth == round(s['misalignment_truth_rad'][k] * ARCMIN_PER_RAD, 3)
        assert est == round(s['misalignment_estimate_rad'][k] * ARCMIN_PER_RAD, 3)
        assert err == pytest.approx(s['misalignment_error_rad'][k] * ARCMIN_PER_RAD, abs=1.5e-3)
        assert sig == round(s['misalignment_sigma_rad'][k] * ARCMIN_PER_RAD, 3)
    assert f"at t = {s['scored_at_s']:.2f} s" in text and '- complete: yes' in text
    for name in sizes:
        assert f'](plots/{name})' in text
    assert '**alignment_filter**' in text and 'rejections by reason:' in text


def test_replay_without_truth_plain_progress_and_plots(truthless_replay):
    bag, out, p = truthless_replay
    s = json.loads((out / 'summary.json').read_text())
    # without truth there is nothing to score (and this branch's summary calls that incomplete)
    assert s['lost_total'] == 0 and all('nothing to score' in x for x in s['problems']), s['problems']
    assert p.returncode == (0 if s['complete'] else 1), p.stderr
    lines = [x for x in p.stderr.splitlines() if x.startswith('replay: t = ')]
    assert lines and '\r' not in p.stderr
    assert lines[-1].endswith('(done)')
    t, total = (float(x) for x in LINE.search(lines[-1]).groups())
    assert t == pytest.approx(s['sim_time_s'], abs=0.005) and total == pytest.approx(14.0)
    sizes = _pngs(out / 'plots')
    # the replay's own bag has the filter's outputs, its input the ship and the LDV
    assert set(sizes) == {'misalignment.png', 'states.png', 'consistency.png', 'motion.png'}
    text = (out / 'report.md').read_text()
    assert 'No misalignment score' in text or 'No truth in the input' in text
    est = estimates_from_bag(out / 'bag')
    last = text[text.index('Last estimate in the bag'):]
    for k, axis in enumerate(AXES):
        row = next(x for x in last.splitlines() if x.startswith(f'| {axis} |'))
        shown = [float(c) for c in row.strip('|').split('|')[1:]]
        assert shown == [round(est['misalignment'][-1, k] * ARCMIN_PER_RAD, 3),
                         round(est['sigma'][-1, k] * ARCMIN_PER_RAD, 3)]


def test_plot_bag_on_a_bag_without_a_run(truthless_replay, tmp_path):
    bag, _, _ = truthless_replay
    p = subprocess.run([str(ROOT / 'scripts/plot_bag.sh'), str(bag), '--out', str(tmp_path / 'p')],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert set(_pngs(tmp_path / 'p')) == {'misalignment.png', 'states.png', 'consistency.png', 'motion.png'}
    assert (tmp_path / 'p' / 'report.md').exists()
    only = subprocess.run([str(ROOT / 'scripts/plot_bag.sh'), str(bag), '--out', str(tmp_path / 'q'),
                           '--topics', '/ship/odom', '/ldv/twist'], capture_output=True, text=True, timeout=300)
    assert only.returncode == 0, only.stderr
    assert set(_pngs(tmp_path / 'q')) == {'motion.png'}
    bad = subprocess.run([str(ROOT / 'scripts/plot_bag.sh'), str(tmp_path / 'nothing')],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and 'no such file' in bad.stderr


def test_air_data_run_plots_and_report(tmp_path):
    out = tmp_path / 'air'
    p = subprocess.run([str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'seed004', '--out', str(out),
                        '--set', 'duration_s=12.0'], capture_output=True, text=True, timeout=400)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    s = json.loads((out / 'summary.json').read_text())
    last = [x for x in p.stderr.splitlines() if x.startswith('run_graph: t = ')][-1]
    assert float(LINE.search(last).group(1)) == pytest.approx(s['sim_time_s'], abs=0.005)
    assert re.search(r'Mach \d\.\d{3} \u00b1 \d\.\d{3}, alpha -?\d+\.\d\d \u00b1 \d+\.\d\d deg', last), last
    sizes = _pngs(out / 'plots')
    assert 'air_data.png' in sizes and sizes['air_data.png'] > 20_000
    text = (out / 'report.md').read_text()
    a = s['air_data']
    for name, scale in (('mach', 1.0), ('alpha (deg)', 180 / np.pi), ('wind_east (m/s)', 1.0)):
        key = {'mach': 'mach', 'alpha (deg)': 'alpha_rad', 'wind_east (m/s)': 'wind_east_mps'}[name]
        row = next(x for x in text.splitlines() if x.startswith(f'| {name} |'))
        rms, err, sig = (float(c) for c in row.strip('|').split('|')[1:])
        assert rms == float(f"{a['rms'][key] * scale:.4g}")
        assert (err, sig) == (float(f"{a['last'][key][0] * scale:.4g}"), float(f"{a['last'][key][1] * scale:.4g}"))
    assert '![Air data](plots/air_data.png)' in text
