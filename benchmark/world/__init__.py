"""The synthetic world: scenarios, the simulated hand and box, tasks, grip policy, truth."""
