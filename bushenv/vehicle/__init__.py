"""Vehicle inputs and outputs for the half car: pure functions of arrays, no environment.

| module            | what                                                                   |
|-------------------|------------------------------------------------------------------------|
| ``roads``         | two correlated ISO 8608 tracks, a pothole on one side, a bump on both  |
| ``steering``      | ISO 7401 step and pulse steer, the NHTSA fishhook, ISO 3888-1 lane change |
| ``single_track``  | linear single-track model and the quasi-static lateral load transfer   |
| ``comfort``       | ISO 2631-1 frequency weightings Wk, Wd and the weighted RMS            |

Every generator takes a sample time ``dt_s`` and returns time-major arrays: ``(T,)`` for one
signal, ``(T, 2)`` for the two wheel tracks (column 0 left, column 1 right, ISO 8855 axes: x
forward, y left, z up). ``docs/vehicle-inputs.md`` lists the parameters and their sources.
"""
