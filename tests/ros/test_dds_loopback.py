"""DDS on the loopback interface only (config/dds/fastdds.xml, exported by scripts/env.sh): while a
node exchanges messages with the test's own participant, no socket of either process is bound to
an address other than 127.0.0.1 (Fast DDS's built-in transports bind to 0.0.0.0 and to every
interface's address)."""
from __future__ import annotations

import ipaddress
import os
import time
from pathlib import Path

from nav_msgs.msg import Odometry
from support.ros_driving import spin_until

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_ros import convert, qos, topics


def _hex_address(text: str) -> str:
    """The local address of a /proc/net/{udp,tcp}[6] line ('0100007F' -> '127.0.0.1'): the
    kernel prints the address in host order, 32-bit words for IPv6."""
    raw = bytes.fromhex(text)
    words = b''.join(raw[i:i + 4][::-1] for i in range(0, len(raw), 4))
    return str(ipaddress.ip_address(words))


def inet_sockets(pid: int) -> list[tuple[str, str, int]]:
    """(protocol, local address, port) of every IP socket the process holds (its fds matched by
    inode against its network namespace's /proc tables)."""
    inodes = set()
    for fd in Path(f'/proc/{pid}/fd').iterdir():
        try:
            link = os.readlink(fd)
        except OSError:
            continue
        if link.startswith('socket:['):
            inodes.add(link[8:-1])
    found = []
    for proto in ('udp', 'udp6', 'tcp', 'tcp6'):
        table = Path(f'/proc/{pid}/net/{proto}')
        if not table.exists():
            continue
        for line in table.read_text().splitlines()[1:]:
            f = line.split()
            if f[9] in inodes:
                addr, port = f[1].split(':')
                found.append((proto, _hex_address(addr), int(port, 16)))
    return found


def test_hex_addresses_decode_as_the_kernel_prints_them():
    assert _hex_address('0100007F') == '127.0.0.1'
    assert _hex_address('00000000') == '0.0.0.0'
    assert _hex_address('0202000A') == '10.0.2.2'
    assert _hex_address('00000000000000000000000001000000') == '::1'


def test_dds_sockets_are_bound_to_loopback_only(ros):
    node, start = ros
    got: list[Odometry] = []
    pub = node.create_publisher(Odometry, topics.SHIP_ODOM, qos.STREAM)
    node.create_subscription(Odometry, topics.MASTER_ODOM, got.append, qos.STREAM)
    proc = start('master_ins_node')
    spin_until(node, lambda: pub.get_subscription_count() >= 1
               and node.count_publishers(topics.MASTER_ODOM) >= 1)
    time.sleep(1.0)
    ships = pipeline.ship_samples(scenario.load('catapult_paper'))[:50]
    for s in ships:
        pub.publish(convert.ship_to_msgs(s)[0])
    spin_until(node, lambda: len(got) == len(ships))       # the loopback transports carry data
    assert proc.poll() is None
    for pid, who in ((proc.pid, 'master_ins_node'), (os.getpid(), 'the test process')):
        socks = [s for s in inet_sockets(pid) if s[0].startswith('udp')]
        assert socks, f'{who} has no UDP socket: are its sockets visible at all?'
        outside = [s for s in inet_sockets(pid) if not ipaddress.ip_address(s[1]).is_loopback]
        assert not outside, f'{who} has sockets off the loopback interface: {outside}'
