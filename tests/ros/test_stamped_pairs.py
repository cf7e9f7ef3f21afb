"""StampPairer: halves of a sample paired by stamp; what never pairs is counted by reason, and a
run whose node dropped unpaired halves (its bound reached) is reported by the launcher."""
from __future__ import annotations

import json

from alignment_ros.launch import unpaired_drops
from alignment_ros.stamped_pairs import StampPairer


def test_pairs_in_any_arrival_order():
    p = StampPairer()
    assert p.add_a(1, 'a1') is None and p.add_b(2, 'b2') is None
    assert p.add_b(1, 'b1') == ('a1', 'b1') and p.add_a(2, 'a2') == ('a2', 'b2')
    assert p.counts() == {'out_of_order': 0, 'unpaired_dropped': 0}


def test_the_bound_drops_the_oldest_halves_and_counts_them():
    p = StampPairer(max_pending=3)
    for t in range(1, 6):                        # 5 a-halves, no b: 2 over the bound
        assert p.add_a(t, f'a{t}') is None
    assert sorted(p.a) == [3, 4, 5]
    assert p.counts()['unpaired_dropped'] == 2
    assert p.add_b(1, 'b1') is None              # its half is gone: it waits, never pairs
    assert p.add_b(3, 'b3') == ('a3', 'b3')
    assert p.add_b(2, 'b2') is None and p.counts()['out_of_order'] == 0   # b2 waits (bounded)


def test_a_pair_older_than_the_last_is_rejected():
    p = StampPairer()
    p.add_a(5, 'a5')
    assert p.add_b(5, 'b5') == ('a5', 'b5')
    p.add_a(4, 'a4')
    assert p.add_b(4, 'b4') is None and p.counts()['out_of_order'] == 1


def test_the_launcher_reads_the_nodes_drops(tmp_path):
    (tmp_path / 'stats').mkdir()
    (tmp_path / 'stats' / 'ldv_node.json').write_text(json.dumps({'rejected': {'unpaired_dropped': 7}}))
    (tmp_path / 'stats' / 'slave_ins_node.json').write_text(json.dumps({'rejected': {'unpaired_dropped': 0}}))
    (tmp_path / 'stats' / 'master_ins_node.json').write_text(json.dumps({'published': {}}))
    assert unpaired_drops(tmp_path) == {'ldv_node': 7}
