"""No function in core/, plugin/ or addon/ is over 100 lines (issue #11),
checked with scripts/check_function_length.py, which is first shown to
catch a long C++ and a long Python function."""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(ROOT, "scripts", "check_function_length.py")


def run(*paths):
    return subprocess.run([sys.executable, CHECK, *paths], cwd=ROOT, capture_output=True, text=True)


def test_the_checker_finds_a_101_line_function_in_cpp_and_python(tmp_path):
    body = "".join(f"    x += {i};\n" for i in range(101))
    (tmp_path / "long.cpp").write_text("int long_one(int x) {\n" + body + "    return x;\n}\n")
    (tmp_path / "long.py").write_text("def long_one(x):\n" + body.replace(";", "") + "    return x\n")
    result = run(str(tmp_path))
    assert result.returncode == 1
    assert "long.cpp" in result.stdout and "long.py" in result.stdout


def test_no_function_in_core_plugin_or_addon_is_over_100_lines():
    result = run("core", "plugin", "addon")
    assert result.returncode == 0, result.stdout
