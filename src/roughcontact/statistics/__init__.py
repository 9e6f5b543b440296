"""Statistics of surfaces and contact fields: geometric representativity, contact clusters."""
