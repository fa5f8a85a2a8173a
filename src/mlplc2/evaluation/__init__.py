"""Evaluation: model outputs held against ground truth, bottom up.

``truth`` (the one ground-truth type and its loader) -> ``record`` (the one recorder of per-frame
outputs) -> ``match`` (the one matcher, the false-alarm and false-warning rules) -> ``score`` (the
scores of one run: the paper's object metrics, the clip outcome and the warning metrics).
"""
