"""The package's ctypes declarations (firemedium/_abi.py) against the C header they transcribe: a C program
compiled against plugin/abi/include/firemedium.h prints every struct's size and each of its fields' offsets, and
the version and status constants; ctypes must agree with all of them (a field added to the header and not here, or
out of order, would have the package read the wrong bytes)."""

import re
import shutil
import subprocess
import tempfile
import unittest
import ctypes as C
from pathlib import Path

from firemedium import _abi as abi

ROOT = Path(__file__).resolve().parents[2]
HEADER = ROOT / "plugin" / "abi" / "include" / "firemedium.h"


def structs():
    """The ctypes structs named as the header's typedefs."""
    text = HEADER.read_text()
    names = set(re.findall(r"typedef struct (Fm\w+) \{", text))
    found = {n: getattr(abi, n) for n in names if isinstance(getattr(abi, n, None), type)}
    return names, found


class Header(unittest.TestCase):
    def test_every_struct_and_field_lies_where_the_header_puts_it(self):
        cc = shutil.which("cc") or shutil.which("gcc")
        if cc is None:
            self.skipTest("no C compiler")
        names, found = structs()
        # Every struct the header declares is here (FmApi's function table included).
        self.assertEqual(sorted(names - set(found)), [], "structs of the header missing from _abi.py")
        lines = []
        for name, cls in sorted(found.items()):
            lines.append(f'printf("{name} size %zu\\n", sizeof({name}));')
            for field, *_ in cls._fields_:
                lines.append(f'printf("{name}.{field} %zu\\n", offsetof({name}, {field}));')
        consts = ["FM_ABI_MAJOR", "FM_ABI_MINOR", "FM_OK", "FM_INVALID_ARGUMENT", "FM_INVALID_PARAMETER",
                  "FM_DATASET", "FM_UNSUPPORTED", "FM_PANIC"]
        for c in consts:
            lines.append(f'printf("{c} %llu\\n", (unsigned long long)({c}));')
        src = "#include <stddef.h>\n#include <stdio.h>\n#include \"firemedium.h\"\nint main(void) {\n" + \
            "\n".join(lines) + "\nreturn 0;\n}\n"
        with tempfile.TemporaryDirectory() as d:
            c_file, exe = Path(d) / "layout.c", Path(d) / "layout"
            c_file.write_text(src)
            r = subprocess.run([cc, "-std=c99", "-I", str(HEADER.parent), str(c_file), "-o", str(exe)],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
        got = dict(line.rsplit(" ", 1) for line in out.splitlines())
        for name, cls in found.items():
            self.assertEqual(int(got[f"{name} size"]), C.sizeof(cls), f"sizeof({name})")
            for field, *_ in cls._fields_:
                self.assertEqual(int(got[f"{name}.{field}"]), getattr(cls, field).offset, f"{name}.{field}")
        self.assertEqual((int(got["FM_ABI_MAJOR"]), int(got["FM_ABI_MINOR"])), (abi.ABI_MAJOR, abi.ABI_MINOR))
        statuses = [int(got[c]) for c in consts[2:]]
        self.assertEqual(statuses, [abi.OK, abi.INVALID_ARGUMENT, abi.INVALID_PARAMETER, abi.DATASET,
                                    abi.UNSUPPORTED, abi.PANIC])


if __name__ == "__main__":
    unittest.main()
