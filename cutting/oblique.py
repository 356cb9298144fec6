"""Oblique cutting per edge element: the cutting, thrust and passive forces of a chip of thickness h and width b
cut by an edge of normal rake gamma_n and inclination lambda_s, with the ploughing of a rounded edge.

The model (chosen over Kienzle-Victor's per-component tables because skiving's working rake runs from +20 to about
-60 deg along the edge and through the generating window, where the handbook's straight-line rake rule (-1.5 % per
degree about +6 deg) is not known to hold, and no citable kf1.1/mf, kp1.1/mp for gear steels was at hand):

* **The oblique transformation of orthogonal cutting** (Armarego and Whitfield, Annals of the CIRP 34/1 (1985) 65;
  Budak, Altintas and Armarego, J. Eng. Ind. 118 (1996) 216; Altintas, Manufacturing Automation, 2nd ed., CUP
  2012, section 2.4). With the shear stress tau_s, the normal shear angle phi_n, the normal friction angle beta_n
  (tan beta_n = tan beta_a cos eta_c) and Stabler's chip flow rule eta_c = lambda_s, per unit chip area::

      S   = sqrt(cos^2(phi_n + beta_n - gamma_n) + tan^2(eta_c) sin^2(beta_n))
      K_c = tau_s / sin(phi_n) * (cos(beta_n - gamma_n) + tan(eta_c) tan(lambda_s) sin(beta_n)) / S
      K_t = tau_s / (sin(phi_n) cos(lambda_s)) * sin(beta_n - gamma_n) / S
      K_p = tau_s / sin(phi_n) * (cos(beta_n - gamma_n) tan(lambda_s) - tan(eta_c) sin(beta_n)) / S

  (K_c: along the cutting velocity; K_t: thrust, normal to the cut surface; K_p: passive, in the cut surface normal
  to the velocity). With lambda_s = 0 they are Merchant's orthogonal forces and K_p = 0.
* **The shear angle** by Merchant's relation phi_n = 45 deg - (beta_n - gamma_n) / 2 (Merchant, J. Appl. Phys. 16
  (1945) 267). It runs to zero near gamma_n = beta_a - 90 deg; below ``rake_floor`` the rake is held (a guess: a
  stagnant zone of workpiece material forms ahead of strongly negative rake faces and acts as the rake, so the
  force grows less than the relation says; see the parameter table in ``assets/materials.toml``).
* **The size effect and the absolute level from Kienzle's table**: tau_s(h) is set so that at the table's reference
  tool (rake +6 deg, no inclination) K_c equals kc(h) = kc1.1 h^-mc of the cited row. Every force of the model is
  therefore kc(h) times a geometric factor: the table's force where the tool is the table's, Merchant's change with
  the rake and the inclination elsewhere (+1.95 % per degree of negative rake about +6 deg at beta_a = 30 deg,
  against the handbook's 1.5 %: docs/forces.md).
* **The rounded edge** (radius r_beta): below the stagnation point, ``min_chip_ratio`` r_beta under the uncut
  surface's far side, the material is pushed under the edge and not cut (the minimum chip thickness h_min): the
  sheared chip is h - h_min, and the edge ploughs with the edge forces K_ce, K_te [N/mm] per unit width wherever it
  engages (Altintas' linear edge-force model, scaled with r_beta). A chip thinner than h_min takes only the edge
  forces.

There is no speed dependence: the table holds at 100 m/min, and no data for the gear steels at other speeds were at
hand (the model's dependence would be a guess).

Energy: the shear forces do work K_c (h - h_min) b per unit length of cut, the thrust and passive forces none (they
are normal to the velocity), the edge K_ce b: :func:`chip_energy`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from cutting.errors import InputError, Problem
from cutting.materials import MATERIALS_PATH, REFERENCE_RAKE_DEG, Material, material

#: the edge radius r_beta [mm] of a tool whose job gives none (the form mills, the face-contour head's elements, the
#: lathe's tool): the skiving cutter's ``[cutter] edge_radius`` default, a guess (ground and honed carbide or coated
#: HSS edges have 5-30 um; docs/forces.md)
DEFAULT_EDGE_RADIUS = 0.010

#: chips thinner than this [mm] take kc of this thickness where no edge radius bounds them (kc1.1 h^-mc grows
#: without bound; h kc(h) does not, so the force stays finite either way)
H_FLOOR = 1e-4


@dataclass(frozen=True)
class CuttingModel:
    """The oblique model's parameters that are not the material's Kienzle row (the table's ``[cutting_model]``):
    ``friction_angle`` beta_a [rad], ``rake_floor`` [rad], ``min_chip_ratio`` h_min / r_beta, the edge forces
    ``edge_cutting`` and ``edge_thrust`` [N/mm] of an edge of radius ``edge_reference_radius`` [mm]."""

    friction_angle: float
    rake_floor: float
    min_chip_ratio: float
    edge_cutting: float
    edge_thrust: float
    edge_reference_radius: float


_MODEL_KEYS = {
    "friction_angle_deg": (0.0, 60.0),
    "rake_floor_deg": (-60.0, 0.0),
    "min_chip_ratio": (0.0, 1.0),
    "edge_cutting_N_per_mm": (0.0, 1e3),
    "edge_thrust_N_per_mm": (0.0, 1e3),
    "edge_reference_radius_mm": (1e-4, 0.2),
}


def load_cutting_model(path: Path = MATERIALS_PATH) -> CuttingModel:
    """The table's ``[cutting_model]``, checked: each key present and within its physical range, each with a source."""
    with open(path, "rb") as f:
        row = tomllib.load(f).get("cutting_model", {})
    problems, sources = [], row.get("sources", {})
    for key, (lo, hi) in _MODEL_KEYS.items():
        v = row.get(key)
        if not isinstance(v, int | float) or not lo <= v <= hi:
            problems.append(Problem(f"cutting_model.{key}", v, f"must be a number in [{lo:g}, {hi:g}]", "see docs"))
        if not sources.get(key):
            problems.append(Problem(f"cutting_model.sources.{key}", None, "every value needs its source", "cite it"))
    if problems:
        raise InputError(problems, str(path))
    return CuttingModel(
        math.radians(row["friction_angle_deg"]),
        math.radians(row["rake_floor_deg"]),
        float(row["min_chip_ratio"]),
        float(row["edge_cutting_N_per_mm"]),
        float(row["edge_thrust_N_per_mm"]),
        float(row["edge_reference_radius_mm"]),
    )


@dataclass(frozen=True)
class ObliqueForces:
    """The three-component model of one material and one edge: ``material`` (Kienzle's row), ``model`` (the
    table's oblique parameters) and the edge radius ``edge_radius`` r_beta [mm] (0: a sharp edge)."""

    material: Material
    model: CuttingModel
    edge_radius: float = 0.0

    @property
    def min_chip(self) -> float:
        """h_min [mm]: the layer under the stagnation point that the edge ploughs and does not cut."""
        return self.model.min_chip_ratio * self.edge_radius

    @property
    def edge_coefficients(self) -> tuple[float, float]:
        """(K_ce, K_te) [N/mm]: the ploughing forces per unit width, along the velocity and normal to the cut
        surface (linear in r_beta from the table's reference edge)."""
        s = self.edge_radius / self.model.edge_reference_radius
        return self.model.edge_cutting * s, self.model.edge_thrust * s

    def shear_angle(self, rake: np.ndarray | float) -> np.ndarray:
        """phi_n [rad] by Merchant's relation at the normal rake (held at the floor below it), orthogonal friction."""
        g = np.maximum(rake, self.model.rake_floor)
        return np.pi / 4 - (self.model.friction_angle - g) / 2

    def factors(self, rake, inclination) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The oblique forces per unit chip area divided by tau_s: (K_c, K_t, K_p) / tau_s at normal rake ``rake``
        and inclination ``inclination`` [rad] (arrays alike)."""
        g = np.maximum(np.asarray(rake, dtype=float), self.model.rake_floor)
        lam = np.asarray(inclination, dtype=float)
        eta = lam  # Stabler's rule
        beta_n = np.arctan(math.tan(self.model.friction_angle) * np.cos(eta))
        phi = np.pi / 4 - (beta_n - g) / 2  # Merchant, with the normal friction angle
        s = np.sqrt(np.cos(phi + beta_n - g) ** 2 + (np.tan(eta) * np.sin(beta_n)) ** 2)
        base = 1.0 / (np.sin(phi) * s)
        kc = base * (np.cos(beta_n - g) + np.tan(eta) * np.tan(lam) * np.sin(beta_n))
        kt = base * np.sin(beta_n - g) / np.cos(lam)
        kp = base * (np.cos(beta_n - g) * np.tan(lam) - np.tan(eta) * np.sin(beta_n))
        return kc, kt, kp

    @cached_property
    def _reference(self) -> float:
        """K_c / tau_s of the table's tool (rake +6 deg, no inclination)."""
        return float(self.factors(math.radians(REFERENCE_RAKE_DEG), 0.0)[0])

    @property
    def reference_factor(self) -> float:
        """K_c / tau_s of the table's tool (rake +6 deg, no inclination): tau_s(h) = kc(h) / this."""
        return self._reference

    def shear_stress(self, h) -> np.ndarray | float:
        """tau_s(h) [N/mm^2] that gives the table's kc(h) at the table's tool (rake +6 deg, no inclination); a float
        for a float h (the co-simulation asks once per engagement)."""
        floor = max(self.min_chip, H_FLOOR)
        if isinstance(h, float | int):
            return self.material.kc11 * max(float(h), floor) ** (-self.material.mc) / self._reference
        hh = np.maximum(np.asarray(h, dtype=float), floor)
        return self.material.kc11 * hh ** (-self.material.mc) / self._reference

    def coefficients(self, h, rake, inclination) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K_c, K_t, K_p) [N/mm^2] at uncut chip thickness ``h`` [mm], normal rake and inclination [rad]."""
        tau = self.shear_stress(h)
        kc, kt, kp = self.factors(rake, inclination)
        return tau * kc, tau * kt, tau * kp

    def element(self, h, b, rake, inclination) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The forces [N] of edge elements (arrays alike) cutting a chip ``h`` [mm] thick and ``b`` [mm] wide (normal
        to the velocity, in the cut surface): cutting along the velocity, thrust normal to the cut surface (pushing
        tool and workpiece apart), passive in the cut surface normal to the velocity (on the workpiece along the
        edge's part normal to the velocity where lambda_s > 0). Elements with h <= 0 take none."""
        h = np.asarray(h, dtype=float)
        b = np.asarray(b, dtype=float)
        kc, kt, kp = self.coefficients(h, rake, inclination)
        sheared = np.maximum(h - self.min_chip, 0.0) * b
        engaged = (h > 0) * b
        ce, te = self.edge_coefficients
        return kc * sheared + ce * engaged, kt * sheared + te * engaged, kp * sheared

    def chip_energy(self, h, b, rake, inclination, length) -> float:
        """The work [J] of cutting a chip ``h`` x ``b`` over a path ``length`` [mm] (arrays alike, summed): the
        shear work K_c (h - h_min) b L plus the edge's ploughing K_ce b L (N mm -> J)."""
        kc, _, _ = self.coefficients(h, rake, inclination)
        ce, _ = self.edge_coefficients
        h = np.asarray(h, dtype=float)
        work = (kc * np.maximum(h - self.min_chip, 0.0) + ce * (h > 0)) * np.asarray(b) * np.asarray(length)
        return float(np.sum(work)) * 1e-3


def oblique_forces(key: str, edge_radius: float = 0.0, path: Path = MATERIALS_PATH) -> ObliqueForces:
    """The three-component model of the table's material ``key`` for an edge of radius ``edge_radius`` [mm]."""
    return ObliqueForces(material(key, path), load_cutting_model(path), edge_radius)


@lru_cache(maxsize=64)
def material_forces(row: Material, edge_radius: float = DEFAULT_EDGE_RADIUS) -> ObliqueForces:
    """The three-component model of the material ``row`` for an edge of radius ``edge_radius`` [mm], the table's
    ``[cutting_model]`` read once (the machines other than the skiving one ask for it at every table and tick)."""
    return ObliqueForces(row, load_cutting_model(), float(edge_radius))


def element_directions(
    tangent: np.ndarray, velocity: np.ndarray, away: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per edge element (arrays (..., 3)): the unit cutting direction (the velocity's), the cut surface's normal
    towards the tool's side (the side of ``away``, e.g. the rake face's normal or the direction from the generated
    surface into the chip), the passive direction (the edge tangent's part normal to the velocity) and the
    inclination lambda_s = asin(t . v / |v|) [rad]."""
    v = velocity / np.maximum(np.linalg.norm(velocity, axis=-1, keepdims=True), 1e-300)
    t = tangent / np.linalg.norm(tangent, axis=-1, keepdims=True)
    along = np.sum(t * v, axis=-1, keepdims=True)
    p = t - along * v
    p /= np.maximum(np.linalg.norm(p, axis=-1, keepdims=True), 1e-300)
    n = np.cross(p, v)
    n *= np.where(np.sum(n * away, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    return v, n, p, np.arcsin(np.clip(along[..., 0], -1.0, 1.0))
