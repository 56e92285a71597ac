"""Session set-up shared by every test.

pytest-xdist exports ``COLUMNS=80`` to its workers; deformap's consoles honour ``COLUMNS`` (a user's
choice wins over the wide default for pipes), so the CLI tests, which read whole lines, would see
rich wrap them at 80 columns under ``-n`` and not without. The tests run as a pipe would.
"""

import os

os.environ.pop("COLUMNS", None)
