"""The evaluation (design §6): ground truth, baseline and table-driven renders of one scene, compared
per pixel in CIEDE2000, with render times, so that error at equal spp and at equal time show."""
