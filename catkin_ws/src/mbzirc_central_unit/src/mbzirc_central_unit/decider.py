"""Decider: the base of the per-role deciders (UGV, blanket UAV, water UAVs and their indoor phase).

Each decider reads and changes the strategy's shared parts: its params, the bookkeeping (goals, searches,
failures), floor ownership and the router. `Strategy` makes one of each and hands them over.
"""
from __future__ import annotations

from .bookkeeping import Bookkeeping
from .command import StrategyParams
from .ownership import FloorOwnership
from .transit import Router


class Decider:
    def __init__(self, params: StrategyParams, book: Bookkeeping, owners: FloorOwnership, router: Router) -> None:
        self.p = params
        self.book = book
        self.owners = owners
        self.router = router
