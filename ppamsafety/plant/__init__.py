"""The plant: geometry, muscles, pneumatics, rigid-body dynamics, assembled ODE.

Modules (one concept each): :mod:`.layout` (packed parameter vector for the
compiled kernels), :mod:`.geometry`, :mod:`.muscle`, :mod:`.torque`,
:mod:`.pneumatics`, :mod:`.dynamics`, :mod:`.model`.
"""
