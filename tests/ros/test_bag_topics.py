"""BagTopics: the topics asked for, read in one pass, give what reading each on its own gives;
each is deserialised once; topics_of reuses what holds the topics and reads what does not."""
from __future__ import annotations

from geometry_msgs.msg import Vector3Stamped
from rclpy.serialization import deserialize_message, serialize_message

from alignment_ros.bag import BagWriter, read_bag
from alignment_ros.bag_topics import BagTopics, topics_of

NS = 1_000_000_000


def _bag(path):
    with BagWriter(path) as w:
        for topic in ('/a', '/b', '/c'):
            w.add_topic(topic, 'geometry_msgs/msg/Vector3Stamped')
        for k in range(30):
            m = Vector3Stamped()
            m.header.stamp.sec, m.header.stamp.nanosec = 1, k
            m.vector.x = float(k)
            w.write(('/a', '/b', '/c')[k % 3], serialize_message(m), NS + k)
    return path


def test_one_pass_gives_each_topic_as_reading_it_alone(tmp_path):
    path = _bag(tmp_path / 'bag')
    have = BagTopics(path, ('/a', '/c', '/absent'))
    for topic in ('/a', '/c'):
        alone = list(read_bag(path, (topic,)))
        assert have.raw(topic) == alone
        assert [m.vector.x for m in have.decoded(topic)] == [
            deserialize_message(m.data, Vector3Stamped).vector.x for m in alone]
    assert [m.vector.x for m in have.decoded('/a')] == [0.0, 3.0, 6.0, 9.0, 12.0, 15.0, 18.0, 21.0, 24.0, 27.0]
    assert have.raw('/absent') == [] and have.decoded('/absent') == []
    assert have.decoded('/a') is have.decoded('/a')          # deserialised once


def test_topics_of_reuses_what_holds_the_topics_and_reads_the_rest(tmp_path):
    path = _bag(tmp_path / 'bag')
    have = BagTopics(path, ('/a', '/b'))
    assert topics_of(have, ('/b',)) is have
    more = topics_of(have, ('/c',))
    assert more is not have and more.path == path and len(more.raw('/c')) == 10
    assert len(topics_of(path, ('/a',)).raw('/a')) == 10
