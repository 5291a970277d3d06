"""Physical jaws (SPEC §6): rigid pads, grasp axes, frictionless contact, converged quality.

Pipeline: :mod:`.geometry` (pads, axes, first touch) → :mod:`.contact` (the contact
problem of one axis on the gauged boundary compliance of :mod:`deformclosure.contact`,
traced exactly in σ by :func:`deformclosure.contact.solve.trace_contact`) → :mod:`.limit`
(elastic limit over the critical distance), :mod:`.friction` (Coulomb pads: the frictional
squeeze and the holding force and torque, SPEC §9) →
:mod:`.landscape` (release over axes; with friction, the moves' dissipation and the
release work of :mod:`.release_work`, SPEC §9) and :mod:`.noise` (what the mesh resolves) →
:mod:`.optimize` (σ*) → :mod:`.refine` (convergence, error, verdict) → with friction
:mod:`.friction_grasp` (every level read with ``Q = min(U_A^μ, U_L)``, the hold at σ*). At finite strain
(SPEC §8) :mod:`.large_deformation` (exact-gap curves of a neo-Hookean part) and
:mod:`.finite_strain_grasp` (σ*, Q* on the linear escape path's sub-landscape). The planner over
grasp axes is :mod:`deformclosure.planning.pads`.
"""

from .contact import GraspCurve, PadContact
from .friction import FrictionalCurve, frictional_grasp
from .geometry import FirstTouch, GraspAxis, Pad, first_touch
from .optimize import PadGraspResult, optimize_pads
from .refine import RefinedPadGrasp, pad_grasp, richardson

__all__ = ["Pad", "GraspAxis", "FirstTouch", "first_touch", "PadContact", "GraspCurve",
           "frictional_grasp", "FrictionalCurve",
           "optimize_pads", "PadGraspResult", "pad_grasp", "RefinedPadGrasp", "richardson"]
