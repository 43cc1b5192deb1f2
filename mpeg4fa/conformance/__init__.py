"""The conformance suite: vectors and expected results as data, a reference model, a runner, reports."""
