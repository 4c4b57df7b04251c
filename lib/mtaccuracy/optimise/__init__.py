"""Optimisers that know nothing of what they optimise.

``ga``: a genetic algorithm batched over independent runs (real or binary encoding, fixed or
adaptive rates), for any vectorised objective.
"""

from .ga import *  # noqa: F403
