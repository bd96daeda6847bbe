"""The engines that advance a :class:`carom.World`: each one a package beside the others,
behind the protocol of :mod:`carom.engines.base`."""
