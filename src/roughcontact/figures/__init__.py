"""Figures: the registry of the pipeline's figures, the common style, one module per figure family."""
