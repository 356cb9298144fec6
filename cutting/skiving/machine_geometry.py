"""The skiving machine's geometry as built: where its axes really are, which the CNC does not know (issue 43).

The CNC commands the nominal kinematics (the setting sheet's ratios, the pass's centre distance, the swivel head at
the shaft angle); the machine as built places the tool a little elsewhere. Each error is one first-order term of the
forward kinematics from the axes (cutter angle B1, work angle B2, carriage P3, radial slide X) to the cutter frame
in the blank frame (ISO 230-1 names what each one is and how it is tested):

    blank <- spindle:   the work spindle's synchronous error motion (once per revolution: a radial offset and a
                        tilt of the turning blank about its mid-face point), composed with the clamping's
    spindle <- head:    Rz(-(B2 + work phase)), then the cutter centre at (X + centre_distance_offset + cx P3,
                        cutter_offset_error + cy P3,  P3 + e sin(2 pi P3 / p + phi))
                        (cx, cy: the carriage's squareness to the work axis; e, p, phi: the lead screw's periodic error,
                        one period a screw turn, its phase at mid face)
    head <- cutter:     Rx(shaft angle + shaft_angle_error) Rz(B1 + cutter phase)

and the spindles' encoders: the ideal kinematics take the axes as the CNC holds them, at their encoders' readings,
so each spindle stands behind its command by what its encoder reads ahead (``skive run`` reads them in each
structure's controllers instead: a chain of gears reads none).

Both the ideal kinematics (`skive cut`: :meth:`cutting.skiving.kinematics.SkivingSetup.machine_pose`, compiled in
:func:`cutting.skiving.exact_solve._ideal`) and the simulated machine (`skive run`:
:func:`virtual_machine.runtime.machine_run.relative_pose`) go through these same terms. The signatures each leaves
on the gear are derived in docs/machine_geometry.md.

Units here: mm and rad (squareness and the spindle's tilt as mm per mm); the job gives deg, mm and mm per 100 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from cutting.skiving.tooling import _tilt, frame


@dataclass(frozen=True)
class MachineGeometry:
    """The machine's geometric errors (all 0: the machine as designed).

    shaft_angle_error: the swivel head's real angle minus the set shaft angle [rad]
    centre_distance_offset: the real centre distance minus the commanded one [mm] (positive: the axes farther apart)
    cutter_offset_error: the cutter centre off the axes' common perpendicular, along the machine's y [mm]
    carriage_squareness_x, carriage_squareness_y: the carriage's travel off parallel to the work axis, towards +x
        (the centre distance) and +y, per unit of travel [mm/mm], zero at mid face
    lead_screw_periodic_error: the carriage's periodic position error [mm], one period a screw turn
        (``lead_screw_pitch`` [mm]), its phase at mid face ``lead_screw_periodic_phase`` [rad]
    work_spindle_radial_error: the work spindle's once-per-revolution radial error motion [mm]: the turning blank's
        centre that far off the axis of rotation, towards ``work_spindle_radial_phase`` [rad] (an angle of the
        blank's frame as the clamping's: 0 is the centre of space 0)
    work_spindle_tilt_error: its once-per-revolution tilt error motion [rad]: the turning blank's axis tilted about
        its mid-face point, its face lifted most at ``work_spindle_tilt_phase`` [rad]
    tool_encoder_eccentricity, work_encoder_eccentricity: the spindles' encoders read their shafts e sin(B + phase)
        ahead [rad] (a graduation off its shaft's centre: once per turn), B the spindle's angle; the axes held at the
        encoders' readings stand that much behind (:meth:`encoder_errors`; in `skive run` the controllers read them)
    axial_offset, axial_rate: the cutter centre off the commanded carriage position along the work axis [mm], and its
        change per mm of travel [mm/mm] (zero at mid face): a pass's thermal drift along z
        (:meth:`cutting.skiving.thermal_drift.ThermalDrift.pass_geometry`; no job key of its own)
    """

    shaft_angle_error: float = 0.0
    centre_distance_offset: float = 0.0
    cutter_offset_error: float = 0.0
    carriage_squareness_x: float = 0.0
    carriage_squareness_y: float = 0.0
    lead_screw_periodic_error: float = 0.0
    lead_screw_periodic_phase: float = 0.0
    lead_screw_pitch: float = 10.0
    work_spindle_radial_error: float = 0.0
    work_spindle_radial_phase: float = 0.0
    work_spindle_tilt_error: float = 0.0
    work_spindle_tilt_phase: float = 0.0
    tool_encoder_eccentricity: float = 0.0
    tool_encoder_phase: float = 0.0
    work_encoder_eccentricity: float = 0.0
    work_encoder_phase: float = 0.0
    axial_offset: float = 0.0
    axial_rate: float = 0.0

    @property
    def exact(self) -> bool:
        """Whether the machine is as designed (every error 0)."""
        return not any(
            getattr(self, f.name) for f in fields(self) if not f.name.endswith(("_phase", "lead_screw_pitch"))
        )

    def head_offset(self, s: np.ndarray) -> np.ndarray:
        """The cutter centre's offset from the commanded (X, 0, P3) in the spindle's (non-rotating) frame at
        carriage positions ``s`` [mm] (n,): (n, 3) [mm]."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        wave = 2 * math.pi / self.lead_screw_pitch
        return np.stack(
            [
                self.centre_distance_offset + self.carriage_squareness_x * s,
                self.cutter_offset_error + self.carriage_squareness_y * s,
                self.axial_offset
                + self.axial_rate * s
                + self.lead_screw_periodic_error * np.sin(wave * s + self.lead_screw_periodic_phase),
            ],
            -1,
        )

    def encoder_errors(self, b1: np.ndarray, b2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """What the tool's and the work's encoders read ahead of their shafts at spindle angles ``b1``, ``b2`` [rad]."""
        return (
            self.tool_encoder_eccentricity * np.sin(b1 + self.tool_encoder_phase),
            self.work_encoder_eccentricity * np.sin(b2 + self.work_encoder_phase),
        )

    def compiled(self) -> list[float]:
        """What :func:`cutting.skiving.exact_solve._ideal` reads beyond the nominal pose: the offset's terms (y
        offset, cx, cy, e, 2 pi / p, phi), the encoders' (tool e, phase, work e, phase) and the axial drift's (offset,
        rate); the centre distance's offset and the shaft angle's error go into the nominal ones."""
        return [
            self.cutter_offset_error,
            self.carriage_squareness_x,
            self.carriage_squareness_y,
            self.lead_screw_periodic_error,
            2 * math.pi / self.lead_screw_pitch,
            self.lead_screw_periodic_phase,
            self.tool_encoder_eccentricity,
            self.tool_encoder_phase,
            self.work_encoder_eccentricity,
            self.work_encoder_phase,
            self.axial_offset,
            self.axial_rate,
        ]

    def spindle_placement(self) -> np.ndarray:
        """The turning blank's placement by the spindle's synchronous error motion, (3, 4): tilted about its
        mid-face point, then moved off the axis (as :func:`cutting.skiving.tooling.blank_frame` places a clamping;
        the tilt here an angle, the clamping's a runout at the reference diameter)."""
        e, phase = self.work_spindle_radial_error, self.work_spindle_radial_phase
        turn = _tilt(self.work_spindle_tilt_error, self.work_spindle_tilt_phase)
        return frame(turn, (e * math.cos(phase), e * math.sin(phase), 0.0))

    def without_errors(self) -> MachineGeometry:
        """The machine as designed (its screw's pitch kept)."""
        return MachineGeometry(lead_screw_pitch=self.lead_screw_pitch)
