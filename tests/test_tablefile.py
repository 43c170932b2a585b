"""Every CSV reader goes through servotune.tablefile: one error type, file and line named."""

from __future__ import annotations

import pytest

from servotune.chatter import read_frf_csv
from servotune.friction.identify import read_friction_csv
from servotune.structure.io import MatrixFileError, read_coordinates, read_dof_map
from servotune.structure.ports import PortError, read_ports
from servotune.tablefile import TableFileError, read_table

# (reader, good header and first row, a bad second row, the column and value the message names)
READERS = [
    (read_frf_csv, "f_hz,re_xx_m_per_n,im_xx_m_per_n\n10,1e-8,-1e-9\n20,2e-8,-2e-9\n",
     "30,3e-8,oops\n", "im_xx_m_per_n"),
    (read_friction_csv, "v_m_per_s,f_n\n0.01,1200\n", "0.02,oops\n", "f_n"),
    (read_coordinates, "node,x,y,z\n1,0,0,0\n", "2,0,oops,0\n", "coordinate"),
]


@pytest.mark.parametrize("reader, good, bad, named", READERS)
def test_a_bad_value_is_named_with_its_line_and_the_common_error(tmp_path, reader, good, bad,
                                                                   named):
    path = tmp_path / "data.csv"
    path.write_text("# measured 2026\n\n" + good + bad)
    line = 2 + len(good.splitlines()) + 1          # comment, blank line, the good lines
    with pytest.raises(TableFileError) as info:
        reader(path)
    message = str(info.value)
    assert message.startswith(f"{path}, line {line}: ") and named in message


@pytest.mark.parametrize("reader, error", [(read_frf_csv, TableFileError),
                                           (read_friction_csv, TableFileError),
                                           (read_coordinates, MatrixFileError),
                                           (read_dof_map, MatrixFileError),
                                           (read_ports, PortError)])
def test_a_missing_or_empty_file_is_a_table_file_error(tmp_path, reader, error):
    with pytest.raises(error, match="cannot read"):
        reader(tmp_path / "missing.csv")
    empty = tmp_path / "empty.csv"
    empty.write_text("# only a comment\n\n")
    with pytest.raises(error, match="empty"):
        reader(empty)
    assert issubclass(error, TableFileError) and issubclass(error, ValueError)


def test_rows_keep_their_file_lines_and_the_header_is_normalised(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(" Port , NODE ,Direction\n\n# skipped\nwp,12,X\ntool,  7 ,y\n")
    table = read_table(path, "ports file")
    assert table.header == ("port", "node", "direction")
    assert table.lines == (4, 5)
    assert table.records() == [{"port": "wp", "node": "12", "direction": "X"},
                               {"port": "tool", "node": "7", "direction": "y"}]
    with pytest.raises(TableFileError, match="needs a header row and at least 3"):
        read_table(path, "ports file", min_rows=3)
    with pytest.raises(TypeError):
        read_table(path, "ports file", error=ValueError)
