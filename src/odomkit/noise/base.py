"""The one noise-model protocol every vehicle's noise implements, and its registry.

A noise model answers four questions about a log's steps (a
:class:`~odomkit.kinematics.BodySteps`, step k going from row k to row k+1); the engines
(the covariance recursion, Kelly's transition matrix, Monte Carlo) ask only these, never
which class they hold:

1. :meth:`NoiseModel.input_variances`: the variances of the model's own *raw inputs* over
   each step (a wheel's travel error, a gyro's integrated rate error, ...), shape (n, r);
2. :meth:`NoiseModel.input_jacobian`: ∂(Δd, Δθ)/∂(raw inputs) of each step, (n, 2, r),
   so the white covariance of the body motion is Q = J diag(var) Jᵀ
   (:meth:`NoiseModel.input_cov`) and a Monte Carlo draw is J diag(σ) z;
3. for the systematic (*bias*) part, constant over a run: the parameters' variances
   (:meth:`NoiseModel.bias_variances`, (p,)) and the sensitivity of each step's body motion
   to them (:meth:`NoiseModel.bias_jacobian`, (n, 2, p));
4. for direct-heading odometry (a compass measures θ instead of integrating it): the
   variance of each heading sample (:meth:`NoiseModel.heading_variances`), and how a
   bias parameter moves every measured heading (:meth:`NoiseModel.bias_heading`, (p,):
   a heading offset, θ_k = θ_meas,k + δ for every k);
5. for white noise that moves the position alone (a sideways slip): the variance of each
   step's displacement across the track (:meth:`NoiseModel.lateral_variances`, (n,)),
   which the engines add apart from the recursion (:mod:`odomkit.propagate.lateral`).

A new noise model is one frozen dataclass subclassing :class:`NoiseModel` in one module,
decorated with :func:`register`; the robot-file reader (:mod:`odomkit.io.robotfile`) finds
its ``[noise]`` keys there (its dataclass fields), and :class:`NoiseSet` combines it with
the others.

Every field name says whether it is a standard deviation (``sigma_*``), a variance
(``var_*``) or a variance density (``k_*``, ``alpha_*``, ``psd_*``), as GTSAM does at
construction: nothing is ambiguous between σ and σ².

Fitting a model to data (``odomkit fit-noise``) needs its *variance parameters*: the
numbers the first-order covariance is linear in. :meth:`NoiseModel.variance_parameters`
gives them by field name and :meth:`NoiseModel.from_variances` rebuilds a model from
them. The field name decides the map (:func:`variance_power`):

==========================  ================================  =====================
field                       meaning                           variance parameter
==========================  ================================  =====================
``sigma_*``                 standard deviation                σ²  (field squared)
``k_*``                     √(variance per metre) [m^½]       k²  (field squared)
``var_*``, ``psd_*``,       variance, spectral density,       the field as it is
``alpha_*``                 variance per metre
==========================  ================================  =====================
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, ClassVar, Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.robot import ROBOT_TYPES

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps
    from odomkit.noise.wheel import WheelInputs
    from odomkit.robot import Robot

__all__ = [
    "NoiseKind",
    "NoiseModel",
    "NoiseSet",
    "NOISE_MODELS",
    "register",
    "noise_fields",
    "sym2",
    "require_non_negative",
    "steps_input",
    "variance_power",
]

NoiseKind = Literal["white", "bias"]


def require_non_negative(obj: object) -> None:
    """Every numeric field of a noise dataclass is a finite number ≥ 0 (strings, e.g. a
    mode, are left to the class)."""
    owner = type(obj).__name__
    for f in fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        if not isinstance(value, str):
            validate.non_negative(value, f"{owner}.{f.name}")


def sym2(q00: ArrayLike, q01: ArrayLike, q11: ArrayLike) -> NDArray[np.float64]:
    """Stack the three distinct entries of symmetric 2×2 matrices, shape (..., 2, 2)."""
    a, b, c = np.broadcast_arrays(np.asarray(q00, dtype=float), np.asarray(q01, dtype=float),
                                  np.asarray(q11, dtype=float))
    # One stack instead of four strided writes: about 5x faster on cache-sized chunks.
    return np.stack([a, b, b, c], axis=-1).reshape(a.shape + (2, 2))


_SQUARED_PREFIXES = ("sigma_", "k_")
_LINEAR_PREFIXES = ("var_", "psd_", "alpha_")


def variance_power(name: str) -> int:
    """2 when a noise field is a standard deviation or its density (``sigma_*``, ``k_*``:
    the variance parameter is its square), 1 when it is already a variance or a variance
    density (``var_*``, ``psd_*``, ``alpha_*``); ModelError for a name that says neither.

    Examples
    --------
    >>> variance_power("k_left"), variance_power("psd_gyro")
    (2, 1)
    """
    if name.startswith(_SQUARED_PREFIXES):
        return 2
    if name.startswith(_LINEAR_PREFIXES):
        return 1
    raise ModelError(f"noise field {name!r} says neither a standard deviation (sigma_*, k_*) "
                     "nor a variance (var_*, psd_*, alpha_*)")


def steps_input(steps: BodySteps, key: str, owner: object) -> NDArray[np.float64]:
    """A raw per-step input of ``steps`` (e.g. ``d_left``), or a ModelError naming it."""
    try:
        return np.asarray(steps.inputs[key], dtype=float)
    except KeyError:
        raise ModelError(f"{type(owner).__name__} needs the per-step input {key!r}, which the "
                         f"steps of a {type(steps.robot).__name__} do not have") from None


class NoiseModel(ABC):
    """One source of odometry noise (see the module docstring for the protocol).

    Attributes
    ----------
    robot_types : tuple of str
        Robot-file types (``"diff"``, ``"tricycle"``, ...) the model applies to; empty
        means any robot. For a path prediction the first one is the vehicle.
    family : str or None
        The closed-form prediction family this model selects (``"wheel"``, ``"gyro"``,
        ...); None for a model that only joins another (a speed or parameter noise).
    step_map : str or None
        A step map of its own (``"classical"``: rotate, then translate), overriding the
        track's method; such a model combines with no other.
    toml_table : str
        Where its keys live in a robot file: ``"noise"`` or ``"noise.parameters"``.
    position_only : bool
        The model's noise moves the position alone (:meth:`lateral_variances`), with no
        raw input to (Δd, Δθ): it is defined for every step map, so it may join a model
        with a step map of its own, and it never stops the per-wheel fast path.
    per_sample : bool
        The model's variances are per *sample* (per log row: a steering angle or a
        compass reading with its own error at every row), not per metre, second or run:
        over a stretch of travel its covariance depends on how many samples there are.
        A log's rows say that; a planned path needs the sample period
        (:func:`odomkit.propagate.paths.path_model`).
    """

    robot_types: ClassVar[tuple[str, ...]] = ()
    family: ClassVar[str | None] = None
    step_map: ClassVar[str | None] = None
    toml_table: ClassVar[str] = "noise"
    position_only: ClassVar[bool] = False
    per_sample: ClassVar[bool] = False

    @property
    def kind(self) -> NoiseKind:
        """``"white"`` (fresh every step) or ``"bias"`` (one unknown constant per run)."""
        return "white"

    def check_robot(self, robot: Robot) -> None:
        """Raise :class:`~odomkit.errors.ModelError` unless the model applies to ``robot``."""
        if self.robot_types and robot.type_name not in self.robot_types:
            names = " or ".join(ROBOT_TYPES[t].__name__ for t in self.robot_types)
            raise ModelError(f"{type(self).__name__} applies to a {names} robot, "
                             f"not a {type(robot).__name__}")

    # --- white part ---------------------------------------------------------------
    @abstractmethod
    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """Variances of the raw inputs over steps a … b−1, shape (b − a, r)."""

    @abstractmethod
    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """∂(Δd, Δθ)/∂(raw inputs) of steps a … b−1, shape (b − a, 2, r)."""

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """White covariance of (Δd, Δθ) of steps a … b−1, Q = J diag(var) Jᵀ, (b − a, 2, 2)
        [m², m·rad; m·rad, rad²]. Models override it where a closed expression is faster."""
        jac = self.input_jacobian(steps, a, b)
        return np.einsum("...ik,...k,...jk->...ij", jac, self.input_variances(steps, a, b), jac)

    def input_factor(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """J diag(σ) of steps a … b−1, (b − a, 2, r): a Monte Carlo draw of this model's
        effect on (Δd, Δθ) is this times r standard normals (one per raw input)."""
        return self.input_jacobian(steps, a, b) * np.sqrt(self.input_variances(steps, a, b))[..., None, :]

    def heading_variances(self, steps: BodySteps) -> NDArray[np.float64] | None:
        """Direct-heading odometry: variance of each measured heading sample, (M + 1,)
        [rad²]; None for a model that does not measure heading."""
        return None

    def lateral_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64] | None:
        """Variance of the sideways displacement of steps a … b−1 [m²], (b − a,): white
        noise along each step's unit normal u_k = (−sin θ̄_k, cos θ̄_k), θ̄_k the chord
        direction of the step map (:func:`odomkit.propagate.lateral.lateral_headings`),
        independent of everything else. None for a model without one."""
        return None

    # --- bias part ----------------------------------------------------------------
    def bias_variances(self, robot: Robot) -> NDArray[np.float64]:
        """Variances of the constant-per-run parameters, shape (p,); (0,) when none."""
        return np.zeros(0)

    def bias_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """∂(Δd, Δθ)/∂(bias parameters) of steps a … b−1, shape (b − a, 2, p)."""
        return np.zeros((b - a, 2, 0))

    def bias_heading(self, robot: Robot) -> NDArray[np.float64]:
        """Direct heading: ∂θ_k/∂(bias parameters) of every measured heading, (p,) (the
        same for every k: an offset of the heading sensor). Zero unless a model says so."""
        return np.zeros(self.bias_variances(robot).size)

    # --- variance parameters (fitting) -----------------------------------------------
    def variance_parameters(self, robot: Robot | None = None) -> dict[str, float]:
        """The model's variance parameters by field name: the numbers its first-order
        covariance contribution is linear in (σ and k fields squared, var/psd/alpha
        fields as they are; see :func:`variance_power`). Text fields (a mode) are left
        out.

        With ``robot``, only the parameters that apply to it: a parameter stays when the
        model with unit variance in it alone passes :meth:`check_robot` (a tricycle has
        no right wheel scale).

        Examples
        --------
        >>> from odomkit.noise import WheelNoise
        >>> WheelNoise(0.01, 0.02).variance_parameters()
        {'k_left': 0.0001, 'k_right': 0.0004}
        """
        out: dict[str, float] = {}
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if isinstance(value, str):
                continue
            out[f.name] = float(value) ** variance_power(f.name)
        if robot is None:
            return out
        zero = dict.fromkeys(out, 0.0)
        kept = {}
        for name, var in out.items():
            try:
                self.from_variances({**zero, name: 1.0}).check_robot(robot)
            except ModelError:
                continue
            kept[name] = var
        return kept

    def from_variances(self: N, variances: Mapping[str, float]) -> N:
        """A copy of the model with the given variance parameters (see
        :meth:`variance_parameters`; fields not named keep their value).

        Examples
        --------
        >>> from odomkit.noise import WheelNoise
        >>> WheelNoise(0.01, 0.02).from_variances({"k_left": 0.0009})
        WheelNoise(k_left=0.03, k_right=0.02)
        """
        names = {f.name for f in fields(self)}  # type: ignore[arg-type]
        values = {}
        for name, var in variances.items():
            if name not in names:
                raise ModelError(f"{type(self).__name__} has no field {name!r}")
            var = validate.non_negative(var, f"{type(self).__name__}.{name} variance")
            values[name] = var if variance_power(name) == 1 else float(np.sqrt(var))
        return replace(self, **values)  # type: ignore[type-var]

    def to_dict(self) -> dict[str, float | str]:
        """The model's parameters by field name (a robot file's ``[noise]`` keys)."""
        from dataclasses import asdict

        return asdict(self)  # type: ignore[call-overload, no-any-return]

    def compiled_inputs(self, steps: BodySteps) -> WheelInputs | None:
        """What a compiled engine needs to form Q_k itself, or None (the engine then
        takes :meth:`input_cov` chunk by chunk)."""
        return None


M = TypeVar("M", bound=type[NoiseModel])
N = TypeVar("N", bound=NoiseModel)

NOISE_MODELS: dict[str, type[NoiseModel]] = {}
"""Every registered noise model by class name, in registration order."""


def register(cls: M) -> M:
    """Class decorator: make a noise model known to the robot-file reader."""
    NOISE_MODELS[cls.__name__] = cls
    return cls


def noise_fields(cls: type[NoiseModel]) -> tuple[frozenset[str], frozenset[str]]:
    """(required, optional) robot-file keys of a noise model: its dataclass fields,
    required where they have no default."""
    from dataclasses import MISSING

    required = frozenset(f.name for f in fields(cls)  # type: ignore[arg-type]
                         if f.default is MISSING and f.default_factory is MISSING)
    optional = frozenset(f.name for f in fields(cls)) - required  # type: ignore[arg-type]
    return required, optional


@dataclass(frozen=True)
class NoiseSet:
    """A validated set of independent noise models for one robot.

    Independent white sources add their input covariances; bias parameters stack into one
    parameter vector; at most one model measures heading.

    Parameters
    ----------
    models : tuple of NoiseModel
        Each class at most once; a model with its own ``step_map`` stands alone.
    """

    models: tuple[NoiseModel, ...]

    def __post_init__(self) -> None:
        seen: set[type] = set()
        for model in self.models:
            if not isinstance(model, NoiseModel):
                raise ModelError(f"not an odomkit noise model: {type(model).__name__}")
            if type(model) in seen:
                raise ModelError(f"{type(model).__name__} given twice")
            seen.add(type(model))
        own = [m for m in self.models if m.step_map is not None]
        # Position-only noise (a sideways slip) is defined for every step map.
        if own and sum(not m.position_only for m in self.models) > 1:
            raise ModelError(f"{type(own[0]).__name__} has its own step map and cannot be combined")

    @classmethod
    def of(cls, noise: NoiseModel | Sequence[NoiseModel | None] | NoiseSet | None) -> NoiseSet:
        """A set from one model, a sequence of models (None entries dropped) or a set."""
        if isinstance(noise, NoiseSet):
            return noise
        if noise is None:
            return cls(())
        if isinstance(noise, Sequence) and not isinstance(noise, str):
            return cls(tuple(m for m in noise if m is not None))
        return cls((noise,))  # type: ignore[arg-type]

    def require(self, cls: type[N]) -> N:
        """The model of exactly class ``cls`` in the set; ModelError if there is none."""
        model = self.get(cls)
        if model is None:
            raise ModelError(f"the noise needs a {cls.__name__}")
        return model

    def get(self, cls: type[N]) -> N | None:
        """The model of exactly class ``cls`` in the set, or None."""
        for model in self.models:
            if type(model) is cls:
                return model  # type: ignore[return-value]
        return None

    @property
    def white(self) -> tuple[NoiseModel, ...]:
        """The models with a white part."""
        return tuple(m for m in self.models if m.kind == "white")

    @property
    def bias(self) -> tuple[NoiseModel, ...]:
        """The models with a bias part."""
        return tuple(m for m in self.models if m.kind == "bias")

    @property
    def family(self) -> str | None:
        """The closed-form family the set selects, or None."""
        families = {m.family for m in self.models if m.family is not None}
        return families.pop() if len(families) == 1 else None

    def step_map(self, method: str) -> str:
        """The engines' step map: a model's own (classical) or the track's ``method``."""
        own = [m.step_map for m in self.models if m.step_map is not None]
        return own[0] if own else method

    def check_robot(self, robot: Robot) -> None:
        """Every model applies to ``robot``; a heading-measuring robot gets no
        integrated-heading model and vice versa (each model's own check)."""
        for model in self.models:
            model.check_robot(robot)

    @property
    def body_white(self) -> tuple[NoiseModel, ...]:
        """The white models with raw inputs to (Δd, Δθ) (not the position-only ones)."""
        return tuple(m for m in self.white if not m.position_only)

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """Summed white covariance of (Δd, Δθ) of steps a … b−1, (b − a, 2, 2)."""
        white = self.body_white
        if len(white) == 1:
            return white[0].input_cov(steps, a, b)
        q = np.zeros((b - a, 2, 2))
        for model in white:
            q += model.input_cov(steps, a, b)
        return q

    def input_factor(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """A with A Aᵀ = Q for each step, (b − a, 2, 2): a Monte Carlo draw of the body
        motion is (Δd, Δθ) + A z with z two standard normals.

        Where the raw inputs are two, A is the models' own J diag(σ) side by side (each
        normal is one raw input, as a simulation of the sensors draws it); otherwise the
        Cholesky factor of Q (a zero variance gives a zero column)."""
        parts = [f for f in (m.input_factor(steps, a, b) for m in self.white) if f.shape[-1]]
        if not parts:
            return np.zeros((b - a, 2, 2))
        factor = np.concatenate(parts, axis=-1)
        if factor.shape[-1] == 2:
            return factor
        q = np.einsum("...ik,...jk->...ij", factor, factor)
        chol = np.zeros_like(q)
        chol[..., 0, 0] = np.sqrt(q[..., 0, 0])
        safe = np.where(chol[..., 0, 0] > 0, chol[..., 0, 0], 1.0)
        chol[..., 1, 0] = np.where(chol[..., 0, 0] > 0, q[..., 1, 0] / safe, 0.0)
        chol[..., 1, 1] = np.sqrt(np.maximum(q[..., 1, 1] - chol[..., 1, 0] ** 2, 0.0))
        return chol

    def heading_variances(self, steps: BodySteps) -> NDArray[np.float64] | None:
        """Variance of each measured heading sample (M + 1,), or None."""
        for model in self.models:
            var = model.heading_variances(steps)
            if var is not None:
                return var
        return None

    def lateral_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64] | None:
        """Summed sideways-displacement variance of steps a … b−1 [m²], (b − a,); None
        when no model has one (the engines then add nothing, so their numbers stay as
        they were)."""
        total = None
        for model in self.models:
            var = model.lateral_variances(steps, a, b)
            if var is not None:
                total = var if total is None else total + var
        return total

    def bias_variances(self, robot: Robot) -> NDArray[np.float64]:
        """Stacked bias-parameter variances (p,)."""
        parts = [m.bias_variances(robot) for m in self.bias]
        return np.concatenate(parts) if parts else np.zeros(0)

    def bias_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """Stacked ∂(Δd, Δθ)/∂(bias parameters), (b − a, 2, p)."""
        parts = [m.bias_jacobian(steps, a, b) for m in self.bias]
        return np.concatenate(parts, axis=-1) if parts else np.zeros((b - a, 2, 0))

    def bias_heading(self, robot: Robot) -> NDArray[np.float64]:
        """Stacked ∂θ_k/∂(bias parameters) of a measured heading, (p,)."""
        parts = [m.bias_heading(robot) for m in self.bias]
        return np.concatenate(parts) if parts else np.zeros(0)
