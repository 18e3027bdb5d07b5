"""Model-based hand-object tracking from depth (the paper's §3.1).

* :mod:`fsv.track.camera`: pixel rays in the world frame, projection, the table's depth.
* :mod:`fsv.track.object`: the box's 6-DoF pose by render-and-compare against the depth.
* :mod:`fsv.track.hand`: the articulated hand fitted to the depth the box and table leave unexplained.
* :mod:`fsv.track.contacts`: contacts by proximity of the tracked fingertips to the box surface.
* :mod:`fsv.track.tracker`: the three in sequence over a video (:func:`~fsv.track.tracker.track`)
  from a first-frame :class:`~fsv.track.tracker.TrackInit`.
"""
