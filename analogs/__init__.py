"""Mechanical analogs of liquid slosh declared as Lagrangian components.

A component declares its coordinates, parameters (with units and bounds), the positions
of its masses in the tank frame and its energy and dissipation terms; ``derive`` turns a
model into equations of motion. Models compose with ``+``::

    from analogs import LateralRig, FixedMass, Pendulum, HingeSpring, HingeDamper
    model = LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeSpring("p1") + HingeDamper("p1")
"""

from .component import Attachment, Component, Rig
from .errors import InputError, UnknownNameError
from .fixed_mass import FixedMass
from .hinge import DiaphragmSpring, HingeDamper, HingeSpring, QuadraticDamper, SwingDamper
from .hinge_nonlinear import CubicHingeSpring, HingeFriction, HingeTorqueTerms
from .model import Model, ModelError
from .motion_rig import MotionRig
from .mounted import Mounted
from .parameter import Param, Parameter
from .pendulum import Pendulum, SphericalPendulum
from .rigs import LateralRig, crank_displacement
from .rotary import RotaryOscillator, ThreeDofPendulum
from .rotor import Rotor
from .spacecraft import FreeSpacecraft, body_angular_velocity
from .spec import model_from_spec, spec_of
from .spinning import SpinningRig
from .suspended_mass import SuspendedMass
from .vehicle import VehicleFrame

__all__ = [
    "Attachment",
    "Component",
    "CubicHingeSpring",
    "DiaphragmSpring",
    "FixedMass",
    "FreeSpacecraft",
    "HingeDamper",
    "HingeFriction",
    "HingeSpring",
    "HingeTorqueTerms",
    "InputError",
    "LateralRig",
    "Model",
    "ModelError",
    "MotionRig",
    "Mounted",
    "Param",
    "Parameter",
    "Pendulum",
    "QuadraticDamper",
    "Rig",
    "RotaryOscillator",
    "Rotor",
    "SphericalPendulum",
    "SpinningRig",
    "SuspendedMass",
    "SwingDamper",
    "ThreeDofPendulum",
    "UnknownNameError",
    "VehicleFrame",
    "body_angular_velocity",
    "crank_displacement",
    "model_from_spec",
    "spec_of",
]
