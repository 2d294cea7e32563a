"""The KKL family: the learned Kazantzis-Kravaris-Luenberger observer (paper section 3) at
a fixed gain (:mod:`~observer.kkl.fixed_gain`) and gain-scheduled
(:mod:`~observer.kkl.scheduled`), its maps and their training, banks and hand-overs,
checkpoints and the ONNX export."""

from observer.moved import lent_names

# alias: this package took the path of the old module observer/kkl.py
__getattr__ = lent_names("observer.kkl.fixed_gain")
