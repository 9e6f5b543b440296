"""Surfaces: the self-affine surface generator and the reader of measured topographies."""
