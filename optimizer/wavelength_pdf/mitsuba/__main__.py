"""``python -m wavelength_pdf.mitsuba SCENE.xml [-m VARIANT] [-o OUT.exr] [-D KEY=VALUE] ...``:
the same as ``wavelength-pdf mitsuba`` (:mod:`wavelength_pdf.cli.mitsuba`)."""
import sys

from wavelength_pdf.cli import main

sys.exit(main(["mitsuba", *sys.argv[1:]]))
