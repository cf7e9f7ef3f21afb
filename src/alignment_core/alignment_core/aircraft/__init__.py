"""The aircraft (truth): deck spot and kinematics, flexure, catapult, vibration, flight."""


