"""The arm: a Kinova Gen3-like arm with a translating two-finger gripper."""
