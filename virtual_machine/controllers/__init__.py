"""Controller blocks of the seeds' kinematic structures, one small class per seed element (HAL style).

Every block has parameters (constructor arguments, checked with ``ValueError``), input and output
attributes (pins, documented with units), one ``update(dt)`` that reads the inputs and writes the
outputs, and ``reset()`` that returns its state to the constructed one (parameters are kept).

Pulse trains are signed ``int`` counts of pulses during the servo tick; cumulative counts are named
``position``.  Analog signals are ``float``.  Structures S1-S4 and the thread group wire these blocks
with the seed's element numbers as instance names, one writer per signal, in an explicit order.
"""

from .analog import Key, ParallelSummator, PowerAmplifier
from .converters import AnalogToPulse, CountToAnalog, PulseToAnalog
from .discriminators import PhaseDiscriminator, SignDiscriminator
from .encoder import Encoder
from .hydraulic import HydraulicPulseGenerator, HydraulicSteppingMotor
from .motors import DCMotor, InductionMotor, SynchronousMotor
from .pulses import FrequencyDivider, RateMultiplier, ReferenceGenerator, Summator
from .servo import SpeedRegulator

__all__ = [
    "AnalogToPulse",
    "CountToAnalog",
    "DCMotor",
    "Encoder",
    "FrequencyDivider",
    "HydraulicPulseGenerator",
    "HydraulicSteppingMotor",
    "InductionMotor",
    "Key",
    "ParallelSummator",
    "PhaseDiscriminator",
    "PowerAmplifier",
    "PulseToAnalog",
    "RateMultiplier",
    "ReferenceGenerator",
    "SignDiscriminator",
    "SpeedRegulator",
    "Summator",
    "SynchronousMotor",
]
