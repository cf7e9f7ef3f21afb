"""Air-data estimators (seed 004): the paper's 3-state airspeed filter and the tightly coupled
port-pressure filter, each with EKF / UKF / CKF; inputs from the aligned INS."""
