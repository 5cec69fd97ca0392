"""``python -m wavelength_pdf``: the ``wavelength-pdf`` command."""
import sys

from wavelength_pdf.cli import main

sys.exit(main())
