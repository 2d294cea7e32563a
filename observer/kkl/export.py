"""One step of a KKL observer as an ONNX graph, to run on the vehicle's computer.

The graph is :meth:`KKLObserver.update` followed by :meth:`KKLObserver.predict`, in
float64:

=========  =========  =============================================================
name       shape      meaning
=========  =========  =============================================================
z          (q,)       input: the observer state z_k
y          (p,)       input: the measured powers y_k [W] (NaN, inf or implausible:
                      missing, replaced by h(x_hat), as the numpy observer does)
u          (1,)       input: the input u_k [rad/s^2] applied after this step
x_hat      (n,)       output: the estimate T*(z_k) (phi [rad], phidot [rad/s])
z_next     (q,)       output: z_{k+1} = A z_k + B y_k + Omega(z_k, u_k)
=========  =========  =============================================================

Omega(z, u) = T(f(x_hat, u)) - T(f(x_hat, u_bar)) is zero when u == u_bar, as in the
numpy observer. The graph needs f and h in closed form: a system describes them with
a :class:`StepForm` (``system.step_form()``), the form both the paper's model and the
identified MuJoCo model have. Building the graph needs the ``onnx`` package only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from observer.exceptions import ObserverError
from observer.kkl.fixed_gain import KKLObserver
from observer.kkl.nets import NumpyMLP

OPSET = 17


@dataclass(frozen=True)
class StepForm:
    """f and h of a system in the form the exported graph computes.

    f:  phi'    = phi + a1 r + a2 u + a3 |r| r
        r'      = b1 r + b2 u + b3 |r| r          (r = phidot)
    h:  gain [g(phi + o_i)] over the receiver's photodiodes (offsets o_i; the paper's
        pair: 0 and dphi),  g(phi) = c1 exp(-((phi - m1)/w1)^2) + c2 exp(-((phi + m2)/w2)^2)
        (ledsim.radiometry.optics.response_terms, the same formula; tests/test_export.py checks the
        graph against the numpy observer)

    Attributes:
        coef_phi: (a1 [s], a2 [s^2], a3 [s]); coef_rate: (b1 [-], b2 [s], b3 [s/rad]).
        gain: [W]; response: (c1, m1 [rad], w1 [rad], c2, m2 [rad], w2 [rad]); dphi [rad].
        output_low, output_high: the usable range of each output [W].
        offsets: each photodiode's incidence angle less the state's phi [rad] (None: the
            paper's pair, (0, dphi)).
        ratio_to: h as ratios: each output g(phi + o_i) / g(phi + ratio_to), gain unused
            (one axis of a pan-tilt's quad over its data detector; None: powers).
    """

    coef_phi: tuple[float, float, float]
    coef_rate: tuple[float, float, float]
    gain: float
    response: tuple[float, float, float, float, float, float]
    dphi: float
    output_low: tuple[float, ...]
    output_high: tuple[float, ...]
    offsets: tuple[float, ...] | None = None
    ratio_to: float | None = None

    @property
    def photodiode_offsets(self) -> tuple[float, ...]:
        return (0.0, self.dphi) if self.offsets is None else tuple(self.offsets)


class _Graph:
    """A small builder over ``onnx.helper``: every node gets a fresh name."""

    def __init__(self):
        try:
            import onnx
            from onnx import helper, numpy_helper
        except ImportError:
            raise ObserverError("exporting to ONNX needs the onnx package: "
                                "pip install 'ledsim[onnx]'") from None

        self.onnx, self.helper, self.numpy_helper = onnx, helper, numpy_helper
        self.nodes, self.inits, self._n = [], [], 0

    def name(self, stem: str) -> str:
        self._n += 1
        return f"{stem}_{self._n}"

    def const(self, value, stem: str = "c") -> str:
        arr = np.asarray(value)
        arr = arr.astype(np.int64 if arr.dtype.kind in "iu" else np.float64)
        name = self.name(stem)
        self.inits.append(self.numpy_helper.from_array(arr, name))
        return name

    def op(self, op_type: str, *inputs: str, stem: str | None = None, **attrs) -> str:
        out = self.name(stem or op_type.lower())
        self.nodes.append(self.helper.make_node(op_type, list(inputs), [out], **attrs))
        return out

    def mlp(self, net: NumpyMLP, v: str, stem: str) -> str:
        """``W2 tanh(... tanh(W1 v + b1) ...) + b2`` on a vector (MatMul on 1-D)."""
        h = self.op("Tanh", self.op("Add", self.op("MatMul", v, self.const(net.W1.T,
                                                                           f"{stem}_W1")),
                                    self.const(net.b1, f"{stem}_b1")))
        for i, (W, b) in enumerate(net.mid):
            h = self.op("Tanh", self.op("Add", self.op("MatMul", h, self.const(
                W.T, f"{stem}_Wm{i}")), self.const(b, f"{stem}_bm{i}")))
        return self.op("Add", self.op("MatMul", h, self.const(net.W2.T, f"{stem}_W2")),
                       self.const(net.b2, f"{stem}_b2"), stem=stem)

    def model(self, name: str, inputs: dict, outputs: dict, props: dict | None = None):
        """The checked ``onnx.ModelProto`` of the nodes so far: float64 ``inputs`` and
        ``outputs`` by name and shape (each output an ``Identity`` of the value named),
        ``props`` its metadata."""
        h, dbl = self.helper, self.onnx.TensorProto.DOUBLE
        for key, (value, _) in outputs.items():
            self.nodes.append(h.make_node("Identity", [value], [key]))
        graph = h.make_graph(
            self.nodes, name, [h.make_tensor_value_info(k, dbl, s) for k, s in inputs.items()],
            [h.make_tensor_value_info(k, dbl, s) for k, (_, s) in outputs.items()],
            initializer=self.inits)
        model = h.make_model(graph, opset_imports=[h.make_opsetid("", OPSET)],
                             producer_name="ledsim")
        model.ir_version = 8  # readable by onnxruntime releases of the last few years
        if props:
            h.set_model_props(model, props)
        self.onnx.checker.check_model(model)
        return model

    def component(self, v: str, i: int) -> str:
        """Element ``i`` of a vector, as a vector of one."""
        return self.op("Slice", v, self.const([i]), self.const([i + 1]), self.const([0]))


def _f(g: _Graph, form: StepForm, x: str, u: str) -> str:
    """x' = f(x, u) of :class:`StepForm`, (2,)."""
    phi, r = g.component(x, 0), g.component(x, 1)
    drag = g.op("Mul", g.op("Abs", r), r)

    def lin(coef, base):
        terms = g.op("Add", g.op("Add", g.op("Mul", g.const([coef[0]]), r),
                                  g.op("Mul", g.const([coef[1]]), u)),
                     g.op("Mul", g.const([coef[2]]), drag))
        return terms if base is None else g.op("Add", base, terms)

    return g.op("Concat", lin(form.coef_phi, phi), lin(form.coef_rate, None), axis=0)


def _h(g: _Graph, form: StepForm, x: str) -> str:
    """h(x) of :class:`StepForm`, (n_pd,)."""
    c1, m1, w1, c2, m2, w2 = form.response
    phi = g.component(x, 0)
    pair = g.op("Concat", *(phi if o == 0.0 else g.op("Add", phi, g.const([o]))
                            for o in form.photodiode_offsets), axis=0)

    def gauss(angles, c, shift, width):
        q = g.op("Div", g.op("Add", angles, g.const([shift])), g.const([width]))
        return g.op("Mul", g.const([c]), g.op("Exp", g.op("Neg", g.op("Mul", q, q))))

    def response(angles):
        return g.op("Add", gauss(angles, c1, -m1, w1), gauss(angles, c2, m2, w2))

    if form.ratio_to is not None:  # each over the divisor's response
        divisor = g.op("Add", phi, g.const([form.ratio_to]))
        return g.op("Div", response(pair), response(divisor))
    return g.op("Mul", g.const([form.gain]), response(pair))


def kkl_step_graph(obs: KKLObserver, form: StepForm, name: str = "kkl_step"):
    """The ONNX model (``onnx.ModelProto``) of one step of ``obs`` (module docstring)."""
    g = _Graph()
    q, p, n = obs.q, obs.system.n_output, obs.system.n_state
    if len(form.photodiode_offsets) != p:
        raise ObserverError(f"the step form has {len(form.photodiode_offsets)} photodiodes "
                            f"and the observer {p} outputs: they must match")
    x_hat = g.mlp(obs.decoder_T_star, "z", "decoder_T_star")
    x_hat = g.op("Identity", x_hat, stem="x_hat_value")
    # Missing samples (non-finite or outside the usable range) are held at h(x_hat).
    bad = g.op("Or", g.op("IsNaN", "y"), g.op("IsInf", "y"))
    bad = g.op("Or", bad, g.op("Less", "y", g.const(form.output_low)))
    bad = g.op("Or", bad, g.op("Greater", "y", g.const(form.output_high)))
    y_used = g.op("Where", bad, _h(g, form, x_hat), "y")
    z_next = g.op("Add", g.op("Mul", g.const(obs.eigenvalues, "A"), "z"),
                  g.op("MatMul", y_used, g.const(obs.B.T, "B_T")))
    if obs.use_omega:
        u_bar = g.const([obs.u_bar], "u_bar")
        omega = g.op("Sub", g.mlp(obs.encoder_T, _f(g, form, x_hat, "u"), "encoder_T"),
                     g.mlp(obs.encoder_T, _f(g, form, x_hat, u_bar), "encoder_T_bar"))
        omega = g.op("Where", g.op("Equal", "u", u_bar), g.const(np.zeros(q)), omega)
        z_next = g.op("Add", z_next, omega)
    return g.model(name, {"z": [q], "y": [p], "u": [1]},
                   {"x_hat": (x_hat, [n]), "z_next": (z_next, [q])})
