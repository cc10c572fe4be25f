"""The independent references of the hard cases, one module per kind.

* :mod:`.euler`: a torque-free rigid body, Euler's equations integrated on their own;
* :mod:`.centre_of_mass`: the closed-form motion of the system's centre of mass and the energy in
  its frame;
* :mod:`.off_manifold`: the closed form of the quaternion norm error under Eq. (58), and the
  loader's refusal of an off-unit start;
* :mod:`.crossings`: event instants (sign changes), for flips and masses passing through each other;
* :mod:`.double_cover`: the mirrored scene, u(0) negated;
* :mod:`.solvers`: the same plant integrated by other scipy methods;
* :mod:`.pinv_law`: the Moore-Penrose law with duplicated requirement rows, from the analytic model
  and from each engine's own mass matrix and forces.

None of them uses the plant it judges; each says what it shares with the model, if anything.
"""
