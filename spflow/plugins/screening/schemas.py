"""Dataset contracts of screening results (dims ``qoi``, ``param``).

Every screening result carries the space it screened (``lower``, ``upper``, ``default``, ``unit`` over ``param``,
i.e. it is also a valid SPACE), each parameter's ``group`` (sub-model), selection ``score`` and ``selected`` flag,
the QoI labels (``qoi_variable``, ``qoi_experiment``, ``qoi_pv``, ``qoi_units``, ``qoi_units_squared``) and the
``variance`` of each QoI over the design its parameter was screened in. Units per element
(:mod:`spflow.core.cf_metadata`): the space's in ``unit``, the variance's in ``qoi_units_squared``, Morris statistics'
in ``qoi_units``. The ``selected_space`` stage turns it into the reduced SPACE.
"""

from spflow.core.schema import DatasetSchema, Variable

__all__ = ["SCREENING", "SOBOL_SCREENING", "MORRIS_SCREENING"]

_QP = ("qoi", "param")
_SOBOL = {"S1": "first-order Sobol' index", "S1_conf": "bootstrap half-width of the first-order index",
          "ST": "total Sobol' index", "ST_conf": "bootstrap half-width of the total index",
          "S2": "second-order Sobol' index", "S2_conf": "bootstrap half-width of the second-order index"}
_MORRIS = {"mu": "mean elementary effect", "mu_star": "mean absolute elementary effect",
           "mu_star_conf": "bootstrap half-width of mu_star", "sigma": "standard deviation of the elementary effects"}

_COMMON = {
    "lower": Variable(("param",), units_variable="unit", long_name="lower end of the screened range"),
    "upper": Variable(("param",), units_variable="unit", long_name="upper end of the screened range"),
    "default": Variable(("param",), units_variable="unit", long_name="default value of the parameter"),
    "unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each parameter"),
    "group": Variable(("param",), kind="U", doc="sub-model the parameter was screened with",
                      long_name="sub-model the parameter was screened with"),
    "score": Variable(("param",), units="1", doc="selection score", long_name="selection score"),
    "selected": Variable(("param",), kind="b", doc="kept by the selection rule",
                         long_name="kept by the selection rule"),
    "variance": Variable(_QP, units_variable="qoi_units_squared",
                         doc="QoI variance over the parameter's screening design",
                         long_name="QoI variance over the parameter's screening design"),
    "qoi_variable": Variable(("qoi",), kind="U", long_name="variable of the QoI"),
    "qoi_experiment": Variable(("qoi",), kind="U", long_name="coreflood of the QoI"),
    "qoi_pv": Variable(("qoi",), units="1", allow_nan=True, long_name="injected pore volumes of the QoI"),
    "qoi_units": Variable(("qoi",), kind="U", long_name="UDUNITS unit of the QoI"),
    "qoi_units_squared": Variable(("qoi",), kind="U", long_name="UDUNITS unit of the QoI squared"),
}

#: Any screening result (what ``selected_space`` and the figure need).
SCREENING = DatasetSchema(dims=_QP, variables=_COMMON, attrs=("method",), doc="screening result")

#: Sobol' screening: first-order and total indices with bootstrap half-widths (S2 only with calc_second_order).
SOBOL_SCREENING = DatasetSchema(
    dims=_QP,
    variables=_COMMON
    | {k: Variable(_QP, units="1", long_name=_SOBOL[k]) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    | {k: Variable(("qoi", "param", "param_j"), units="1", required=False, allow_nan=True, long_name=_SOBOL[k])
       for k in ("S2", "S2_conf")},
    attrs=("method",),
    doc="Sobol' indices per QoI and parameter, selection and screened space",
)

#: Morris screening: elementary-effect statistics in QoI units (SALib's unscaled effects: output difference over the
#: step on the unit-scaled box, :func:`.morris.morris_indices`).
MORRIS_SCREENING = DatasetSchema(
    dims=_QP,
    variables=_COMMON | {k: Variable(_QP, units_variable="qoi_units", long_name=_MORRIS[k])
                         for k in ("mu", "mu_star", "mu_star_conf", "sigma")},
    attrs=("method",),
    doc="Morris mu, mu*, sigma per QoI and parameter, selection and screened space",
)
