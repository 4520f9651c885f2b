"""Model parameters: the nondimensional set and the physical set it comes from (docs/model.md).

Nondimensional (paper §2.3, eqs. 13–15): ``e`` restitution, ``omega_s = ω t_c`` stator
frequency (peak stator acceleration ``Γ = omega_s²`` in units of g), ``r_phi = R_φ`` angular
amplitude ratio, ``psi`` torsional phase. Physical: ``t_c = sqrt(U0 / g_eff)`` with
``g_eff = g + F_preload / m_r``; ``r_eff = 2 r_c / 3`` (eq. 2); ``R_d = r_eff Φ0 / U0``;
``R_φ = (r_eff / r_g)² μ / R_d`` (eq. 15); rotor angular velocity in rad/s is ``Ω R_φ Φ0 / t_c``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from ..engine.bounds import MAX_PSI, check_omega_s
from .errors import InputError, plain
from .limits import E_SIGMA, MAX_LOAD

#: Restitution noise that samples the natural measure (docs/model.md "Long-run statistics of
#: chaotic motion"), for ensembles whose scene states none: physically meaningless, a periodic
#: attractor's members still coincide, a chaotic one's spread over the attractor.
NATURAL_E_SIGMA = 1e-9


def number(
    source: str, name: str, value: object, *, positive: bool = False, nonneg: bool = False
) -> float:
    """The one number validator: a finite float from a YAML number or any text ``float()`` reads.

    Accepts ``1e-6``, ``1E300``, ``-2.5e+3`` and ``1_000.5`` whether YAML gave a number or a
    string, and any real number Python code passes (numpy's scalars and 0-d arrays included);
    refuses booleans, other text, NaN and infinities.

    Parameters
    ----------
    source, name : str
        The file (or ``--set``) and the dotted field, for the error message.
    value : object
        What the user wrote.
    positive, nonneg : bool
        Also require ``> 0`` or ``>= 0``.

    Raises
    ------
    InputError
        Naming ``source`` and ``name``.
    """
    value = _scalar(value)
    if isinstance(value, str):
        try:
            x = float(value.strip())
        except ValueError:
            raise InputError(source, name, f"must be a number, got {plain(value)}") from None
    elif isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise InputError(source, name, f"must be a number, got {plain(value)}")
    else:
        try:
            x = float(value)
        except OverflowError:
            raise InputError(source, name, f"must be finite, got {plain(value)}") from None
    if not math.isfinite(x):
        raise InputError(source, name, f"must be finite, got {plain(value)}")
    if positive and not x > 0:
        raise InputError(source, name, f"must be > 0, got {plain(value)}")
    if nonneg and x < 0:
        raise InputError(source, name, f"must be >= 0, got {plain(value)}")
    return x


def _scalar(value: object) -> object:
    """A numpy 0-d array as its one value (what ``np.array(0.4)`` means); anything else as is."""
    if isinstance(value, np.ndarray) and value.shape == ():
        return value.item()
    return value


def whole_number(source: str, name: str, value: object, *, minimum: int = 1) -> int:
    """A whole number ``>= minimum`` (``3``, ``3.0``, ``"1e3"``; not ``2.5`` or ``true``).

    Raises
    ------
    InputError
        Naming ``source`` and ``name``.
    """
    value = _scalar(value)
    if isinstance(value, str):
        value = number(source, name, value)
    if isinstance(value, numbers.Integral) and not isinstance(value, bool | np.bool_):
        value = int(value)
    elif isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_):
        value = int(value) if math.isfinite(value) and float(value).is_integer() else value
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(source, name, f"must be a whole number, got {plain(value)}")
    if value < minimum:
        raise InputError(source, name, f"must be >= {minimum}, got {value}")
    return value


@dataclass(frozen=True)
class Parameters:
    """Nondimensional model parameters (docs/model.md "Variables and scales").

    Parameters
    ----------
    e : float
        Coefficient of restitution, ``0 <= e <= 1`` (eq. 3).
    omega_s : float
        Stator frequency ``ω t_c > 0``.
    r_phi : float
        Angular amplitude ratio ``R_φ > 0`` (eq. 15).
    psi : float
        Phase of the torsional vibration relative to the axial one (eq. 1), radians.
    inertia_ratio : float
        ``J_s / J_r > 0`` for the ``stator_inertia`` effect (eq. 11); ``inf`` means eq. 19.
    mu_ratio : float
        ``μ_static / μ_kinetic >= 1`` for the ``kinetic_static`` effect.
    e_sigma : float
        ``σ_e >= 0``, standard deviation of the per-impact restitution for the
        ``restitution_noise`` effect (docs/model.md "Long-run statistics of chaotic motion").
    load_torque : float
        ``τ_L >= 0``, the constant load torque of the ``load`` effect in units of the friction
        torque at the static normal load, ``μ m_r g_eff r_eff`` (docs/model.md "The motor under load").
    """

    e: float
    omega_s: float
    r_phi: float = 0.01
    psi: float = 0.0
    inertia_ratio: float = math.inf
    mu_ratio: float = 1.0
    e_sigma: float = 0.0
    load_torque: float = 0.0

    def __post_init__(self) -> None:
        """Refuse values outside the model (``e`` in ``[0, 1]``, ``omega_s > 0``, ...), however
        the parameters are made (:meth:`validate`, with the source ``Parameters``)."""
        self.validate("Parameters", "Parameters")

    @classmethod
    def from_mapping(cls, data: dict, source: str = "", prefix: str = "parameters") -> Parameters:
        """Validate a mapping (e.g. a scene's ``parameters:``) into :class:`Parameters`."""
        known = {f.name for f in fields(cls)}
        for key in data:
            if key not in known:
                raise InputError(
                    source,
                    f"{prefix}.{key}",
                    f"unknown parameter (known: {', '.join(sorted(known))})",
                )
        for key in ("e", "omega_s"):
            if key not in data:
                raise InputError(source, f"{prefix}.{key}", "is required")
        vals = {
            k: number(source, f"{prefix}.{k}", v) for k, v in data.items() if k != "inertia_ratio"
        }
        if "inertia_ratio" in data:
            j = data["inertia_ratio"]
            if isinstance(j, str) and j.strip().lower() in ("inf", "infinity", ".inf"):
                vals["inertia_ratio"] = math.inf
            else:
                vals["inertia_ratio"] = number(source, f"{prefix}.inertia_ratio", j)
        try:
            return cls(**vals)
        except InputError as ex:  # name the file and its section, not the class
            field = prefix + ex.field.removeprefix("Parameters")
            raise InputError(source, field, ex.message) from None

    def replaced(self, source: str = "", **values: float) -> Parameters:
        """A copy with some parameters replaced, validated (:meth:`validate`): a sweep's point."""
        params = replace(self, **values)
        params.validate(source)
        return params

    def validate(self, source: str = "", prefix: str = "parameters") -> None:
        """Raise :class:`InputError` for out-of-range values."""
        if not 0.0 <= self.e <= 1.0:
            raise InputError(source, f"{prefix}.e", f"must be in [0, 1], got {self.e}")
        if not self.omega_s > 0.0:
            raise InputError(source, f"{prefix}.omega_s", f"must be > 0, got {plain(self.omega_s)}")
        check_omega_s(source, f"{prefix}.omega_s", self.omega_s)
        if not self.r_phi > 0.0:
            raise InputError(source, f"{prefix}.r_phi", f"must be > 0, got {self.r_phi}")
        if not self.inertia_ratio > 0.0:
            raise InputError(
                source, f"{prefix}.inertia_ratio", f"must be > 0, got {self.inertia_ratio}"
            )
        E_SIGMA.check(source, f"{prefix}.e_sigma", self.e_sigma)
        if not 0.0 <= self.load_torque <= MAX_LOAD:
            raise InputError(
                source,
                f"{prefix}.load_torque",
                f"must be in [0, {MAX_LOAD:g}] friction torques (a hundred times the momentum "
                f"bound tau_L = 1), got {plain(self.load_torque)}",
            )
        if not self.mu_ratio >= 1.0:
            raise InputError(source, f"{prefix}.mu_ratio", f"must be >= 1, got {self.mu_ratio}")
        if abs(self.psi) > MAX_PSI:
            raise InputError(
                source, f"{prefix}.psi", f"must be an angle in radians, got {self.psi}"
            )

    @property
    def gamma(self) -> float:
        """Peak stator acceleration in units of g, ``Γ = omega_s²``."""
        return self.omega_s**2


@dataclass(frozen=True)
class Scales:
    """Conversion from nondimensional to SI units.

    ``time_s = t * t_c``; ``omega_rad_s = Ω * omega_scale`` with ``omega_scale = R_φ Φ0 / t_c``;
    ``length_m = u * U0``; ``torque_Nm = τ * torque`` with ``torque = μ m_r g_eff r_eff`` (docs/model.md
    "The motor under load"); powers in W are ``P * torsion_power`` (torsional terms, units
    ``J_r omega_scale² / t_c``, equal to ``torque * omega_scale``) and ``P * axial_power`` (axial
    terms, units ``m_r g_eff U0 / t_c``).
    """

    t_c: float
    omega_scale: float
    length: float
    g_eff: float
    torque: float = math.nan
    torsion_power: float = math.nan
    axial_power: float = math.nan


@dataclass(frozen=True)
class PhysicalParameters:
    """Dimensional description of a motor (SI units; docs/model.md "Physical conversion").

    Parameters
    ----------
    m_r : float
        Rotor mass [kg].
    r_g : float
        Rotor radius of gyration [m] (``J_r = m_r r_g²``).
    r_c : float
        Contact radius [m] (``r_eff = 2 r_c / 3``, eq. 2).
    mu : float
        Kinetic friction coefficient.
    e : float
        Coefficient of restitution.
    g : float
        Gravitational acceleration [m/s²].
    f : float
        Stator drive frequency [Hz].
    U0 : float
        Axial vibration amplitude [m].
    Phi0 : float
        Torsional vibration amplitude [rad].
    psi : float
        Torsional phase [rad].
    F_preload : float
        Constant spring preload [N], acting as extra gravity.
    load_torque : float
        Constant load torque on the rotor [N·m] (effect ``load``).
    e_sigma : float
        Standard deviation of the per-impact restitution (effect ``restitution_noise``).
    """

    m_r: float
    r_g: float
    r_c: float
    mu: float
    e: float
    g: float
    f: float
    U0: float
    Phi0: float
    psi: float = 0.0
    F_preload: float = 0.0
    load_torque: float = 0.0
    e_sigma: float = 0.0

    @classmethod
    def from_mapping(
        cls, data: dict, source: str = "", prefix: str = "physical"
    ) -> PhysicalParameters:
        """Validate a mapping (a scene's ``physical:``) into :class:`PhysicalParameters`."""
        names = [f for f in cls.__dataclass_fields__]
        for key in data:
            if key not in names:
                raise InputError(
                    source, f"{prefix}.{key}", f"unknown field (known: {', '.join(names)})"
                )
        required = ["m_r", "r_g", "r_c", "mu", "e", "g", "f", "U0", "Phi0"]
        for key in required:
            if key not in data:
                raise InputError(source, f"{prefix}.{key}", "is required")
        vals = {k: number(source, f"{prefix}.{k}", v) for k, v in data.items()}
        p = cls(**vals)
        for key in ("m_r", "r_g", "r_c", "mu", "g", "f", "U0", "Phi0"):
            if not getattr(p, key) > 0.0:
                raise InputError(source, f"{prefix}.{key}", f"must be > 0, got {getattr(p, key)}")
        if not 0.0 <= p.e <= 1.0:
            raise InputError(source, f"{prefix}.e", f"must be in [0, 1], got {p.e}")
        E_SIGMA.check(source, f"{prefix}.e_sigma", p.e_sigma)
        for key in ("F_preload", "load_torque"):
            if getattr(p, key) < 0.0:
                raise InputError(source, f"{prefix}.{key}", f"must be >= 0, got {getattr(p, key)}")
        return p

    def scales(self) -> Scales:
        """Time, angular-velocity and length scales (paper eq. 14)."""
        g_eff = self.g + self.F_preload / self.m_r
        t_c = math.sqrt(self.U0 / g_eff)
        omega_scale = self.r_phi * self.Phi0 / t_c
        torque = self.mu * self.m_r * g_eff * self.r_eff
        return Scales(
            t_c=t_c,
            omega_scale=omega_scale,
            length=self.U0,
            g_eff=g_eff,
            torque=torque,
            torsion_power=torque * omega_scale,
            axial_power=self.m_r * g_eff * self.U0 / t_c,
        )

    @property
    def r_eff(self) -> float:
        """Effective friction radius ``2 r_c / 3`` (eq. 2)."""
        return 2.0 * self.r_c / 3.0

    @property
    def r_phi(self) -> float:
        """``R_φ = (r_eff / r_g)² μ / R_d`` with ``R_d = r_eff Φ0 / U0`` (eq. 15)."""
        r_d = self.r_eff * self.Phi0 / self.U0
        return (self.r_eff / self.r_g) ** 2 * self.mu / r_d

    def to_nondimensional(self) -> Parameters:
        """The four nondimensional parameters ``(e, omega_s, r_phi, psi)`` and the load
        ``τ_L = T_L / (μ m_r g_eff r_eff)`` (docs/model.md "The motor under load")."""
        sc = self.scales()
        return Parameters(
            e=self.e,
            omega_s=2.0 * math.pi * self.f * sc.t_c,
            r_phi=self.r_phi,
            psi=self.psi,
            e_sigma=self.e_sigma,
            load_torque=self.load_torque / sc.torque,
        )

    def as_dict(self) -> dict:
        """The SI values as a plain mapping."""
        return asdict(self)

    @classmethod
    def from_nondimensional(
        cls,
        p: Parameters,
        f: float,
        Phi0: float,
        m_r: float,
        r_g: float,
        r_c: float,
        F_preload: float = 0.0,
        g: float = 9.81,
        load_torque: float = 0.0,
    ) -> PhysicalParameters:
        """The motor whose nondimensional parameters are ``p``, given its drive and rotor.

        The inverse of :meth:`to_nondimensional` (docs/model.md "Physical conversion"):
        ``t_c = ω_s / (2π f)``, ``U0 = g_eff t_c²``, ``R_d = r_eff Φ0 / U0`` and
        ``μ = R_φ R_d (r_g / r_eff)²`` (eq. 15); ``load_torque`` is in N·m.
        """
        g_eff = g + F_preload / m_r
        t_c = p.omega_s / (2.0 * math.pi * f)
        u0 = g_eff * t_c * t_c
        r_eff = 2.0 * r_c / 3.0
        mu = p.r_phi * (r_eff * Phi0 / u0) * (r_g / r_eff) ** 2
        return cls(
            m_r=m_r,
            r_g=r_g,
            r_c=r_c,
            mu=mu,
            e=p.e,
            g=g,
            f=f,
            U0=u0,
            Phi0=Phi0,
            psi=p.psi,
            F_preload=F_preload,
            load_torque=load_torque,
            e_sigma=p.e_sigma,
        )
