"""The paper's protocols: Table 1 (kinematics), Table 2 (learned forces) and their training data."""
