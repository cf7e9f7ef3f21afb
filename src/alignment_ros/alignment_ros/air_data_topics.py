"""Air-data topics topics.py does not name yet: the reference INS's odometry, the port frames,
and the INS topic each `air_data_filter.ins_source` reads."""
from __future__ import annotations

from . import topics

REFERENCE_INS_ODOM = topics.REFERENCE_INS_ODOM
"""A reference INS solution (slave_ins_node, when reference_ins.enabled): nav_msgs/Odometry."""
REFERENCE_INS_TYPE = topics.TOPIC_TYPES[REFERENCE_INS_ODOM]

FADS_PORT_FRAMES = tuple(f'fads_port_{k}' for k in range(len(topics.FADS_PORT_TOPICS)))
"""header.frame_id of /fads/port_k."""

INS_TOPICS = {'aligned': topics.ALIGN_ODOM, 'reference': REFERENCE_INS_ODOM}
"""air_data_filter.ins_source -> the Odometry topic the air-data filter reads."""
