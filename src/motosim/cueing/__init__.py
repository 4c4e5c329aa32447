"""Motion cueing for the platform (roll, pitch, yaw) and vestibular scoring."""
