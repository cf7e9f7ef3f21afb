"""The progress line: plain periodic lines off a terminal, one updating tqdm line on a pseudo-
terminal, nothing when quiet; the final line states the simulation time reached. The estimate is
shown in arcmin (1 mrad = 180 * 60 / pi / 1000 = 3.4377 arcmin)."""
from __future__ import annotations

import fcntl
import io
import os
import pty
import re
import select
import struct
import termios
import time

import pytest

from alignment_ros.progress import Progress, choose_mode

LINE = re.compile(r't = (\d+\.\d\d) / (\d+\.\d\d) s')


def test_plain_lines_rate_limited_and_the_final_line_states_the_end():
    out = io.StringIO()
    p = Progress('run_graph', 12.0, 5.0, stream=out, interval_s=3600.0)
    assert p.mode == 'plain'
    p.update(None, messages=3)            # nothing known of the time yet: no line
    p.update(5.0, messages=10)            # the first: shown
    p.update(6.0, messages=20)            # within the interval: not shown
    p.close(17.0, messages=30)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0].startswith('run_graph: t = 0.00 / 12.00 s') and '10 msgs' in lines[0]
    assert LINE.search(lines[-1]).groups() == ('12.00', '12.00')
    assert '30 msgs' in lines[-1] and lines[-1].endswith('(done)') and 'ETA' not in lines[-1]


def test_rate_eta_and_estimate():
    out = io.StringIO()
    p = Progress('replay', 100.0, 0.0, stream=out, interval_s=0.0)
    p.update(0.0)
    time.sleep(0.6)
    p.update(10.0, estimate=([1e-3, -2e-3, 0.0], [1e-4, 1e-4, 5e-4]))
    line = out.getvalue().splitlines()[-1]
    rtf = float(re.search(r'rtf (\d+\.\d+)', line).group(1))
    assert 10.0 / 1.2 < rtf < 10.0 / 0.6          # 10 sim s over a little more than 0.6 wall s
    m, s = re.search(r'ETA (\d+):(\d\d)', line).groups()
    assert int(m) * 60 + int(s) == pytest.approx(90.0 / rtf, abs=1.0)
    assert 'misalignment 3.44 -6.88 0.00 \u00b1 0.34 0.34 1.72 arcmin' in line


def test_quiet_says_nothing():
    out = io.StringIO()
    p = Progress('record', None, quiet=True, stream=out, interval_s=0.0)
    p.update(1.0, messages=5)
    p.close(2.0, messages=6)
    assert out.getvalue() == '' and p.mode == 'quiet'


def test_without_a_duration_no_percentage_nor_eta():
    out = io.StringIO()
    p = Progress('record', None, stream=out, interval_s=0.0)
    p.update(3.0, messages=4)
    p.close(4.5, messages=9)
    last = out.getvalue().splitlines()[-1]
    assert last.startswith('record: t = 4.50 s') and 'ETA' not in last and '9 msgs' in last


def test_bad_mode_is_refused():
    with pytest.raises(ValueError, match='progress mode'):
        choose_mode(io.StringIO(), mode='fancy')


def _pty(cols: int = 160) -> tuple[int, int]:
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack('HHHH', 24, cols, 0, 0))
    return master, slave


def _drain(fd: int, quiet_s: float = 0.5) -> str:
    """Everything written to the pty until nothing more comes for quiet_s."""
    chunks = []
    while select.select([fd], [], [], quiet_s)[0]:
        try:
            b = os.read(fd, 65536)
        except OSError:
            break
        if not b:
            break
        chunks.append(b)
    return b''.join(chunks).decode(errors='replace')


def test_on_a_terminal_one_updating_line():
    master, slave = _pty()
    stream = os.fdopen(slave, 'w', buffering=1)
    p = Progress('run_graph', 20.0, 1.0, stream=stream)
    assert p.mode == 'tty'
    for k in range(5):
        p.update(1.0 + 4.0 * k, messages=100 * k)
        time.sleep(0.25)
    p.close(21.0, messages=1000)
    stream.flush()
    text = _drain(master)
    stream.close()
    os.close(master)
    assert text.count('\n') <= 2                    # one line, redrawn in place
    assert text.count('\r') >= 3
    final = text.rstrip('\r\n').split('\r')[-1]
    assert LINE.search(final).groups() == ('20.00', '20.00')
    assert final.startswith('100%|') and '| run_graph: t = 20.00 / 20.00 s' in final and '1000 msgs' in final


def test_abandoned_no_final_line():
    out = io.StringIO()
    p = Progress('run_graph', 12.0, 0.0, stream=out, interval_s=3600.0)
    p.update(2.0)
    p.abandon()
    p.update(5.0)
    p.close(12.0)
    assert out.getvalue().splitlines() == ['run_graph: t = 2.00 / 12.00 s']
