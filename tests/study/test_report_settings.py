"""The report records' defaults, for library users, are the schema's (config/schema.yaml)."""

import pytest

from roughcontact.study.config import ConvergenceSettings, SpeedReportSettings, report_section


@pytest.mark.parametrize("record, name", [(SpeedReportSettings, "speed_vs_error"),
                                          (ConvergenceSettings, "influence_convergence")])
def test_report_settings_defaults_are_the_schemas(record, name):
    """A report run without a section (``report_section`` fills in the schema's defaults)
    is the report run with the record's defaults."""
    assert record() == record.from_section(report_section({"reports": {}}, name))
