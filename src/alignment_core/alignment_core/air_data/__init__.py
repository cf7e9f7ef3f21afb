"""Air data physics shared by the simulator and the estimators: the atmosphere of a day,
pitot relations, flow angles, the flush-port pressure model and the FADS solve."""
