"""Ship six-DOF motion truth and the simulation clock."""
