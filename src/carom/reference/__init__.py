"""Slow, obvious reference versions of carom's laws and kernels, for tests and studies."""
