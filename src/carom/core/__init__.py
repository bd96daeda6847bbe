"""Numba kernels: plain floats and arrays in, plain floats and arrays out. No I/O, no objects."""
