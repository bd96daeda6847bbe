"""Scenes the play tests run."""

#: a small pyramid with nothing fired at it: 5 rows of unit boxes on the ground
SMALL_PYRAMID = """
[scene]
title = "Small pyramid"

[world]
dimension = 2
box = [20.0, 12.0]
boundary = "open"
gravity = [0.0, -10.0]

[rigid]
rate = 60.0
substeps = 4

[[materials]]
name = "boxes"
restitution = 0.0
friction = 0.6

[[bodies]]
shape = "box"
size = [40.0, 2.0]
positions = [[10.0, -1.0]]
kind = "static"
material = "boxes"

[[pyramid]]
rows = 5
base = [10.0, 0.0]
size = [1.0, 1.0]
material = "boxes"

[run]
until = 10.0
"""
