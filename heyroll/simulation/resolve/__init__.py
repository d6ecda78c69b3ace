"""Collision resolution as strategies, one per pair type, apart from detection.

* body-body on a track whose metric and gap are constant and linear (the
  circle): the law compiled once per pair, :mod:`heyroll.simulation.events`
  (the hot path);
* body-body anywhere else: :mod:`.local_map`, the law's map at the metric of
  the contact point, read in the run's own type at each collision;
* body-limiter and junction passages: :mod:`.bounds`;
* cluster-body (persistent contact on the circle): Newton's law between
  units, :func:`heyroll.simulation.events.unit_map`.
"""
