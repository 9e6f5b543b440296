"""Foundation: units strings, FFT plans, atomic file output, version. Imports nothing above it."""
