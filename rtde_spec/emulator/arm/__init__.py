"""The arm: joint state, motion profiles and kinematics (the floor the rest stands on)."""
