"""JSON schema of a qpp config (CR-185644 Part III), generated from :class:`qpp.io.config.QppConfig` with the generic machinery of
:mod:`acmm_qpp.config_model`.  ``qpp schema`` prints it."""
from __future__ import annotations

from acmm_qpp.config_model import Generator, header
from qpp.io.config import QppConfig


def qpp_schema() -> dict:
    """Schema of a qpp config (:class:`qpp.io.config.QppConfig`).

    Returns
    -------
    dict
        JSON schema (draft 2020-12); dimensional fields accept a number or a quantity string in
        any unit of the field's dimension.
    """
    return header(QppConfig.model_json_schema(mode="validation", schema_generator=Generator),
                  "qpp config (CR-185644 Part III)")
