"""The articulated hand fitted to the depth the box and the table leave unexplained
(:class:`~fsv.track.hand.tracker.HandTracker`; the method is described there)."""

from fsv.track.hand.config import HandTrackerConfig
from fsv.track.hand.kinematics import HandKinematics
from fsv.track.hand.state import HandFit, HandState
from fsv.track.hand.tracker import HandTracker

__all__ = ["HandFit", "HandKinematics", "HandState", "HandTracker", "HandTrackerConfig"]
