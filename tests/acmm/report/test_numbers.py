"""The report's number formatting (:mod:`acmm.report.numbers`), shared by the HTML report and the
generated blocks of README.md and the guide."""
import pytest

from acmm.report.numbers import fixed, fmt_value, markdown_table, sci, sig


@pytest.mark.parametrize("x, digits, text", [(3986.2, 3, "3 990"), (6644.9, 3, "6 640"), (0.03812, 3, "0.0381"),
                                             (-1.964, 3, "\u22121.96"), (9.996, 3, "10.0"), (0.0495, 2, "0.050"),
                                             (130.0, 3, "130")])
def test_significant_digits(x, digits, text):
    assert sig(x, digits) == text


def test_scientific_and_fixed():
    assert sci(48396.1) == "4.8e4"
    assert sci(2.43e-6) == "2.4e\u22126"
    assert fixed(-0.46802) == "\u22120.468"
    assert fixed(5.0916, 2, sign=True) == "+5.09"
    assert fixed(-0.0001) == "0.000"


def test_fmt_value():
    assert fmt_value(None) == "—"
    assert fmt_value([1.0, 2.5], "{:.1f}") == "[1.0, 2.5]"


def test_markdown_table_aligns_columns():
    assert markdown_table(["a", "b"], [["1", "2"]], "lr") == "| a | b |\n| --- | --: |\n| 1 | 2 |\n"
