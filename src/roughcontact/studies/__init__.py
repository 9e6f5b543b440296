"""Studies built on everything below: accuracy, the κ gap, the reproduction of the paper, verdicts, the report."""
