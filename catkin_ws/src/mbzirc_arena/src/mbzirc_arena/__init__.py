"""mbzirc_arena: the Challenge 3 arena as a team knows it before the trial (see README.md).

Modules: `arena` (the model and its loader), `c3` (the default arena), `buildings` (footprint rules,
classify_fire), `routing` (2D routes around rectangles), `boxes` (airspace boxes), `yaw`, `laser` (a scan's ranges as points), `messages`
(the message constants). Pure Python: no ROS import.
"""
from .arena import Arena, ArenaError, Building, Holder, Home, Opening, arena_from_world, floor_of, load_arena

__all__ = ['Arena', 'ArenaError', 'Building', 'Holder', 'Home', 'Opening', 'arena_from_world', 'floor_of',
           'load_arena']
