"""Aircraft slave IMU at the deck spot: lever arm, misalignment, catapult, sensor errors; truth."""
