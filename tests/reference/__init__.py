"""Independent reference evaluators for the tests; they never import mechcirc."""
