"""Bad measurement CSV files: one table row per case; a new bad input is one more row.

REFUSED rows must give an InputError naming the field (and the fix where there is one), from the
library and from the command line (exit 2, one line, no traceback, nothing written). ACCEPTED
rows are files spreadsheets really write: they must load to the same numbers as the clean file,
with a note where the user must know something.
"""

import numpy as np
import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.measurements import REQUIRED_COLUMNS, load_measurements

N_ROWS = 40


def rows(**changes):
    """A clean record (10 s sampling, rated-ish load, °C) as a list of rows of strings; ``changes``
    maps ``column`` to a function (row index, value) -> new value."""
    table = []
    for i in range(N_ROWS):
        values = {"time_s": 10.0 * i, "I_u": 5.0, "I_v": 5.1, "I_w": 4.9, "I_exc": 0.8, "T_inlet": 20.0,
                  "T_ambient": 19.5, "T_winding_u": 40.0 + 0.1 * i, "T_winding_v": 40.2 + 0.1 * i,
                  "T_winding_w": 40.1 + 0.1 * i, "T_iron": 35.0 + 0.05 * i}
        for column, change in changes.items():
            values[column] = change(i, values[column])
        table.append([f"{values[c]:g}" if isinstance(values[c], float) else str(values[c]) for c in REQUIRED_COLUMNS])
    return table


def csv_bytes(table=None, separator=",", header=None, encoding="utf-8", decimal="."):
    table = rows() if table is None else table
    lines = [separator.join(header or REQUIRED_COLUMNS)]
    lines += [separator.join(cell.replace(".", decimal) for cell in row) for row in table]
    return ("\n".join(lines) + "\n").encode(encoding)


def ragged(extra_cells: int, at: int = 7):
    table = rows()
    table[at] = table[at] + ["1"] * extra_cells if extra_cells > 0 else table[at][:extra_cells]
    return csv_bytes(table)


# (case, file content, text the error must contain)
REFUSED = [
    ("empty file", b"", "empty"),
    ("header only", csv_bytes([]), "no data rows"),
    ("binary file", b"\x00\x01\x02PK\x03\x04" * 50, "binary"),
    ("row with an extra cell", ragged(1), "line 9"),
    ("row with a missing cell", ragged(-1), "line 9"),
    ("decimal commas, comma separated", csv_bytes(separator=",", decimal=","), "decimal commas"),
    ("quoted decimal comma", csv_bytes(rows(I_u=lambda i, v: '"5,5"' if i == 2 else v)), "decimals with '.'"),
    ("column twice", csv_bytes([r + ["1"] for r in rows()], header=[*REQUIRED_COLUMNS, "T_iron"]), "more than once"),
    ("missing column", csv_bytes([r[:-1] for r in rows()], header=REQUIRED_COLUMNS[:-1]), "T_iron"),
    ("misspelt column", csv_bytes(header=[*REQUIRED_COLUMNS[:-1], "T_irn"]), "did you mean 'T_irn'"),
    ("text in a current", csv_bytes(rows(I_u=lambda i, v: "high" if i == 3 else v)), "column I_u, data row 4"),
    ("infinite current", csv_bytes(rows(I_v=lambda i, v: "inf" if i == 5 else v)), "I_v"),
    ("current of 1e300", csv_bytes(rows(I_w=lambda i, v: 1e300 if i == 5 else v)), "rated"),
    ("currents in mA", csv_bytes(rows(I_u=lambda i, v: v * 1000, I_v=lambda i, v: v * 1000,
                                      I_w=lambda i, v: v * 1000)), "mA"),
    ("field current of 1e300", csv_bytes(rows(I_exc=lambda i, v: 1e300 if i == 5 else v)), "I_exc"),
    ("field current in mA", csv_bytes(rows(I_exc=lambda i, v: v * 1000)), "mA"),
    ("negative current", csv_bytes(rows(I_u=lambda i, v: -1.0 if i == 2 else v)), "negative"),
    ("temperatures in kelvin", csv_bytes(rows(**{c: (lambda i, v: v + 273.15) for c in
                                                 ("T_inlet", "T_ambient", "T_winding_u", "T_winding_v",
                                                  "T_winding_w", "T_iron")})), "kelvin"),
    ("sensors only in kelvin", csv_bytes(rows(**{c: (lambda i, v: v + 273.15) for c in
                                                 ("T_winding_u", "T_winding_v", "T_winding_w", "T_iron")})),
     "kelvin"),
    ("mostly out of PT100 range", csv_bytes(rows(T_iron=lambda i, v: -80.0 if i % 3 else v)), "wrong unit"),
    ("time not increasing", csv_bytes(rows(time_s=lambda i, v: 50.0 if i == 6 else v)), "strictly increasing"),
    ("empty input cell", csv_bytes(rows(T_inlet=lambda i, v: "" if i == 4 else v)), "empty cell"),
    ("inlet above PT100 range", csv_bytes(rows(T_inlet=lambda i, v: 350.0 if i == 4 else v)), "PT100"),
    ("time in milliseconds", csv_bytes(rows(time_s=lambda i, v: v * 1000)), "divide it by 1000"),
    ("time in hours", csv_bytes(rows(time_s=lambda i, v: v / 3600)), "multiply it by 3600"),
    ("time steps of 1e300 s", csv_bytes(rows(time_s=lambda i, v: 1e300 * (i + 1))), "time_s must be in seconds"),
    ("header in capitals", csv_bytes(header=[c.upper() for c in REQUIRED_COLUMNS]), "case-sensitive"),
]

# (case, file content, text one of the flags must contain, or None for no flag)
ACCEPTED = [
    ("UTF-8 with byte-order mark", b"\xef\xbb\xbf" + csv_bytes(), None),
    ("Latin-1 header comment", csv_bytes(header=[*REQUIRED_COLUMNS, "Bemerkung"],
                                         table=[r + ["Prüfstand"] for r in rows()], encoding="latin-1"),
     "Latin-1"),
    ("UTF-16 (Excel Unicode text)", csv_bytes(separator="\t", encoding="utf-16"), None),
    ("semicolons", csv_bytes(separator=";"), None),
    ("semicolons and decimal commas", csv_bytes(separator=";", decimal=","), "decimal commas"),
    ("tabs and decimal commas", csv_bytes(separator="\t", decimal=","), "decimal commas"),
    ("Windows line ends", csv_bytes().replace(b"\n", b"\r\n"), None),
    ("a 3-hour gap", csv_bytes(rows(time_s=lambda i, v: v + (10800.0 if i >= 20 else 0.0))), "gap"),
    ("one sensor sample out of range", csv_bytes(rows(T_iron=lambda i, v: 999.0 if i == 3 else v)), "PT100"),
]


@pytest.mark.parametrize("content, named", [c[1:] for c in REFUSED], ids=[c[0] for c in REFUSED])
def test_refused_files_name_the_problem(content, named, tmp_path, capsys):
    path = tmp_path / "data.csv"
    path.write_bytes(content)
    with pytest.raises(InputError) as caught:
        load_measurements(path)
    assert named in str(caught.value)
    out = tmp_path / "est.json"
    assert main(["estimate", str(path), "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("content, flagged", [c[1:] for c in ACCEPTED], ids=[c[0] for c in ACCEPTED])
def test_accepted_files_read_the_same_numbers(content, flagged, tmp_path):
    clean, path = tmp_path / "clean.csv", tmp_path / "data.csv"
    clean.write_bytes(csv_bytes())
    path.write_bytes(content)
    expected = load_measurements(clean).frame
    with pytest.warns() if flagged else _no_warning():
        data = load_measurements(path)
    if flagged:
        assert any(flagged in flag for flag in data.flags), data.flags
    else:
        assert data.flags == []
    common = [c for c in expected.columns if c != "time_s" and c != "T_iron"]
    np.testing.assert_allclose(data.frame[common].to_numpy(), expected[common].to_numpy())


class _no_warning:
    def __enter__(self):
        import warnings

        self._catch = warnings.catch_warnings()
        self._catch.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        return self._catch.__exit__(*exc)


def test_gap_warning_reaches_the_command_line_user(tmp_path, capsys):
    path = tmp_path / "gappy.csv"
    path.write_bytes(csv_bytes(rows(time_s=lambda i, v: v + (10800.0 if i >= 20 else 0.0))))
    main(["estimate", str(path), "--predict-from", "1"])
    assert "warning:" in capsys.readouterr().err
