"""The edits the wavelength-pdf patch makes to an upstream pbrt-v4 checkout.

Each edit names a file (relative to the checkout), an anchor (an exact snippet of upstream
pbrt-v4 at commit 5f7a6068) and what replaces it, and how many times the anchor occurs.
Every replacement carries the marker ``wavelength-pdf patch`` so that an applied edit is
recognized. ``CHECKS`` are anchors that are only verified (the patch relies on them but
does not change them), ``NEW_FILES`` are copied in (destination -> source in this repository).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

MARKER = "wavelength-pdf patch"
UPSTREAM_COMMIT = "5f7a6068"

_HERE = Path(__file__).resolve().parent
_REPO = _HERE.parent.parent


@dataclass(frozen=True)
class Edit:
    """Replace ``count`` occurrences of ``anchor`` in ``path`` with ``replacement``."""

    path: str
    anchor: str
    replacement: str
    count: int = 1


@dataclass(frozen=True)
class Check:
    """``anchor`` must occur in ``path`` (unchanged by the patch); ``why`` says what needs it."""

    path: str
    anchor: str
    why: str


# destination in the checkout -> file of this repository
NEW_FILES = {
    "src/pbrt/wavelength_table.h": _REPO / "wavelength_table" / "include" / "wavelength_table.h",
    "src/pbrt/wavelengthpdf.h": _HERE / "files" / "src" / "pbrt" / "wavelengthpdf.h",
    "src/pbrt/wavelengthpdf.cpp": _HERE / "files" / "src" / "pbrt" / "wavelengthpdf.cpp",
}

_INC = "#include <pbrt/wavelengthpdf.h>  // " + MARKER + "\n"

CHECKS = [
    Check("src/pbrt/util/spectrum.h",
          "    friend struct SOA<SampledWavelengths>;\n"
          "    pstd::array<Float, NSpectrumSamples> lambda, pdf;\n};",
          "wavelengthpdf.h builds SampledWavelengths from arrays with this member layout"),
    Check("src/pbrt/util/spectrum.h",
          "    void TerminateSecondary() {\n"
          "        if (SecondaryTerminated())\n"
          "            return;\n"
          "        // Update wavelength probabilities for termination\n"
          "        for (int i = 1; i < NSpectrumSamples; ++i)\n"
          "            pdf[i] = 0;\n"
          "        pdf[0] /= NSpectrumSamples;\n",
          "the dispersion rule generalizes this termination (keep slot 0, weight 4)"),
]

EDITS = [
    # ---- build: the new source file, for the CPU and (in GPU builds) as CUDA ----------
    Edit("CMakeLists.txt",
         "\n  src/pbrt/options.cpp\n  src/pbrt/paramdict.cpp\n",
         "\n  src/pbrt/options.cpp\n  src/pbrt/wavelengthpdf.cpp  # " + MARKER
         + "\n  src/pbrt/paramdict.cpp\n"),
    Edit("CMakeLists.txt",
         "\n   src/pbrt/options.cpp\n#   src/pbrt/paramdict.cpp\n",
         "\n   src/pbrt/options.cpp\n   src/pbrt/wavelengthpdf.cpp  # " + MARKER
         + "\n#   src/pbrt/paramdict.cpp\n"),
    # ---- command line: the two options, loading the table after InitPBRT -------------
    Edit("src/pbrt/cmd/pbrt.cpp",
         "#include <pbrt/wavefront/wavefront.h>\n",
         "#include <pbrt/wavefront/wavefront.h>\n" + _INC),
    Edit("src/pbrt/cmd/pbrt.cpp",
         "  --wavefront                   Use wavefront volumetric path integrator.\n",
         "  --wavefront                   Use wavefront volumetric path integrator.\n"
         "  --wavelength-pdf <file>       Sample each camera path's four wavelengths from a\n"
         "                                wavelength table (one u, exact inversion, balance\n"
         "                                heuristic over its four densities).\n"
         "  --wavelength-pdf-defensive <s> Mix a uniform share s in [0, 1] into each density\n"
         "                                of the table (removes zero-density gaps).\n"
         "  --wavelength-sampling <name>  emission: sample each camera path's wavelengths from\n"
         "                                the scene's own lamps (their emitted power in four\n"
         "                                equal-mass bands, built at scene load; for spiky\n"
         "                                lamps). visible (default): upstream's sampling.\n"
         "  --emission-weight <w>         With emission: spd (the power alone, default),\n"
         "                                luminance (times ybar) or xyz (times x+y+z).\n"),
    Edit("src/pbrt/cmd/pbrt.cpp",
         "    bool format = false, toPly = false;\n",
         "    bool format = false, toPly = false;\n"
         "    std::string wavelengthPdf, wavelengthPdfDefensive;  // " + MARKER + "\n"
         "    std::string wavelengthSampling, emissionWeight;\n"),
    Edit("src/pbrt/cmd/pbrt.cpp",
         '            ParseArg(&iter, args.end(), "wavefront", &options.wavefront, onError) ||\n',
         '            ParseArg(&iter, args.end(), "wavefront", &options.wavefront, onError) ||\n'
         '            ParseArg(&iter, args.end(), "wavelength-pdf", &wavelengthPdf,  // '
         + MARKER + "\n"
         "                     onError) ||\n"
         '            ParseArg(&iter, args.end(), "wavelength-pdf-defensive",\n'
         "                     &wavelengthPdfDefensive, onError) ||\n"
         '            ParseArg(&iter, args.end(), "wavelength-sampling", &wavelengthSampling,\n'
         "                     onError) ||\n"
         '            ParseArg(&iter, args.end(), "emission-weight", &emissionWeight, onError) ||\n'),
    Edit("src/pbrt/cmd/pbrt.cpp",
         "    // Initialize pbrt\n    InitPBRT(options);\n",
         "    // Initialize pbrt\n    InitPBRT(options);\n"
         "    if (!format && !toPly && !options.upgrade)  // " + MARKER + "\n"
         "        InitWavelengthTable(wavelengthPdf, wavelengthPdfDefensive, wavelengthSampling,\n"
         "                            emissionWeight);\n"),
    # ---- the warning for zero mixture density where a light emits --------------------
    Edit("src/pbrt/scene.cpp",
         "#include <pbrt/shapes.h>\n",
         "#include <pbrt/shapes.h>\n" + _INC),
    Edit("src/pbrt/scene.cpp",
         "void BasicScene::AddLight(LightSceneEntity light) {\n",
         "void BasicScene::AddLight(LightSceneEntity light) {\n"
         "    WarnUnsampledEmission(light.name, light.parameters, &light.loc);  // "
         + MARKER + "\n"),
    Edit("src/pbrt/scene.cpp",
         "int BasicScene::AddAreaLight(SceneEntity light) {\n",
         "int BasicScene::AddAreaLight(SceneEntity light) {\n"
         "    WarnUnsampledEmission(light.name, light.parameters, &light.loc);  // "
         + MARKER + "\n"),
    # ---- --wavelength-sampling emission: where each light was defined, and the table ---
    Edit("src/pbrt/scene.cpp",
         "    lightJobs.push_back(RunAsync(create));\n}\n",
         "    lightJobs.push_back(RunAsync(create));\n"
         "    NoteLightSource(light.name, light.parameters, &light.loc);  // " + MARKER + "\n}\n"),
    Edit("src/pbrt/scene.cpp",
         "            if (area) {\n"
         "                lights.push_back(area);\n"
         "                shapeLights->push_back(area);\n"
         "            }\n",
         "            if (area) {\n"
         "                lights.push_back(area);\n"
         "                shapeLights->push_back(area);\n"
         "                NoteAreaLight(area, areaLightEntity.parameters,  // " + MARKER + "\n"
         "                              &areaLightEntity.loc);\n"
         "            }\n"),
    Edit("src/pbrt/scene.cpp",
         "    for (auto &job : lightJobs)\n"
         "        lights.push_back(job->GetResult());\n",
         "    for (size_t job = 0; job < lightJobs.size(); ++job) {  // " + MARKER + "\n"
         "        lights.push_back(lightJobs[job]->GetResult());\n"
         "        NoteLightSourceCreated(job, lights.back());\n"
         "    }\n"),
    Edit("src/pbrt/cpu/render.cpp",
         "#include <pbrt/cpu/render.h>\n",
         "#include <pbrt/cpu/render.h>\n" + _INC),
    Edit("src/pbrt/cpu/render.cpp",
         "    std::unique_ptr<Integrator> integrator(\n"
         "        parsedScene.CreateIntegrator(camera, sampler, accel, lights));\n",
         "    std::unique_ptr<Integrator> integrator(\n"
         "        parsedScene.CreateIntegrator(camera, sampler, accel, lights));\n"
         "    // The lights are preprocessed (scene bounds): the emission table can be built.\n"
         "    InitEmissionWavelengthTable(lights.data(), lights.size());  // " + MARKER + "\n"),
    Edit("src/pbrt/wavefront/integrator.cpp",
         "#include <pbrt/wavefront/integrator.h>\n",
         "#include <pbrt/wavefront/integrator.h>\n" + _INC),
    Edit("src/pbrt/wavefront/integrator.cpp",
         "    for (Light light : allLights)\n"
         "        light.Preprocess(aggregate->Bounds());\n",
         "    for (Light light : allLights)\n"
         "        light.Preprocess(aggregate->Bounds());\n"
         "    InitEmissionWavelengthTable(allLights.data(), allLights.size());  // " + MARKER + "\n"),
    # ---- CPU integrators: every place that samples the film's wavelengths ------------
    Edit("src/pbrt/cpu/integrators.cpp",
         "#include <pbrt/cpu/integrators.h>\n",
         "#include <pbrt/cpu/integrators.h>\n" + _INC),
    Edit("src/pbrt/cpu/integrators.cpp",  # RayIntegrator and LightPathIntegrator
         "    SampledWavelengths lambda = camera.GetFilm().SampleWavelengths(lu);\n",
         "    SampledWavelengths lambda = SampleCameraWavelengths(camera.GetFilm(), lu);  // "
         + MARKER + "\n",
         count=2),
    Edit("src/pbrt/cpu/integrators.cpp",  # MLT
         "        *lambda = camera.GetFilm().SampleWavelengths(0.5);\n"
         "    else\n"
         "        *lambda = camera.GetFilm().SampleWavelengths(sampler.Get1D());\n",
         "        *lambda = SampleCameraWavelengths(camera.GetFilm(), 0.5);  // " + MARKER + "\n"
         "    else\n"
         "        *lambda = SampleCameraWavelengths(camera.GetFilm(), sampler.Get1D());\n"),
    Edit("src/pbrt/cpu/integrators.cpp",  # SPPM
         "        const SampledWavelengths passLambda = film.SampleWavelengths(uLambda);\n",
         "        const SampledWavelengths passLambda =\n"
         "            SampleCameraWavelengths(film, uLambda);  // " + MARKER + "\n"),
    # ---- CPU integrators: the dispersion rule where they terminate wavelengths -------
    Edit("src/pbrt/cpu/integrators.cpp",  # SimpleVolPathIntegrator
         "    // Terminate secondary wavelengths before starting random walk\n"
         "    lambda.TerminateSecondary();\n",
         "    // Terminate secondary wavelengths before starting random walk\n"
         "    TerminateSecondaryWavelengths(lambda, ray.o, ray.d);  // " + MARKER + "\n"),
    Edit("src/pbrt/cpu/integrators.cpp",  # SPPM visible point: remember the kept slot
         "                     const SampledSpectrum &beta, bool secondaryLambdaTerminated)\n",
         "                     const SampledSpectrum &beta,\n"
         "                     int secondaryLambdaTerminated)  // " + MARKER + "\n"),
    Edit("src/pbrt/cpu/integrators.cpp",
         "        SampledSpectrum beta;\n        bool secondaryLambdaTerminated;\n",
         "        SampledSpectrum beta;\n"
         "        int secondaryLambdaTerminated;  // " + MARKER + ": 0, or 1 + the kept slot\n"),
    Edit("src/pbrt/cpu/integrators.cpp",
         "                        pixel.vp = {isect.p(), wo, bsdf, beta,\n"
         "                                    lambda.SecondaryTerminated()};\n",
         "                        pixel.vp = {isect.p(), wo, bsdf, beta,  // " + MARKER + "\n"
         "                                    SecondaryWavelengthsTerminated(lambda)\n"
         "                                        ? 1 + KeptWavelengthSlot(lambda)\n"
         "                                        : 0};\n"),
    Edit("src/pbrt/cpu/integrators.cpp",
         "                                if (pixel.vp.secondaryLambdaTerminated)\n"
         "                                    photonLambda.TerminateSecondary();\n",
         "                                if (pixel.vp.secondaryLambdaTerminated)  // "
         + MARKER + "\n"
         "                                    TerminateSecondaryWavelengthsAt(\n"
         "                                        photonLambda,\n"
         "                                        pixel.vp.secondaryLambdaTerminated - 1);\n"),
    # ---- materials: the dispersion rule (CPU and GPU) ----------------------------------
    Edit("src/pbrt/materials.h",
         "#include <pbrt/textures.h>\n",
         "#include <pbrt/textures.h>\n" + _INC),
    Edit("src/pbrt/materials.h",  # DielectricMaterial, ThinDielectricMaterial
         "        Float sampledEta = eta(lambda[0]);\n"
         "        if (!eta.template Is<ConstantSpectrum>())\n"
         "            lambda.TerminateSecondary();\n",
         "        if (!eta.template Is<ConstantSpectrum>())  // " + MARKER + "\n"
         "            TerminateSecondaryWavelengths(lambda, ctx.p, ctx.wo);\n"
         "        Float sampledEta = eta(lambda[0]);\n",
         count=2),
    Edit("src/pbrt/materials.cpp",  # CoatedDiffuseMaterial
         "    Float sampledEta = eta(lambda[0]);\n"
         "    if (!eta.template Is<ConstantSpectrum>())\n"
         "        lambda.TerminateSecondary();\n",
         "    if (!eta.template Is<ConstantSpectrum>())  // " + MARKER + "\n"
         "        TerminateSecondaryWavelengths(lambda, ctx.p, ctx.wo);\n"
         "    Float sampledEta = eta(lambda[0]);\n"),
    Edit("src/pbrt/materials.cpp",  # CoatedConductorMaterial
         "    Float ieta = interfaceEta(lambda[0]);\n"
         "    if (!interfaceEta.template Is<ConstantSpectrum>())\n"
         "        lambda.TerminateSecondary();\n",
         "    if (!interfaceEta.template Is<ConstantSpectrum>())  // " + MARKER + "\n"
         "        TerminateSecondaryWavelengths(lambda, ctx.p, ctx.wo);\n"
         "    Float ieta = interfaceEta(lambda[0]);\n"),
    # ---- wavefront integrator (CPU with --wavefront, GPU with --gpu) -------------------
    Edit("src/pbrt/wavefront/camera.cpp",
         "#include <pbrt/wavefront/integrator.h>\n",
         "#include <pbrt/wavefront/integrator.h>\n" + _INC),
    Edit("src/pbrt/wavefront/camera.cpp",
         "            SampledWavelengths lambda = film.SampleWavelengths(lu);\n",
         "            SampledWavelengths lambda = SampleCameraWavelengths(film, lu);  // "
         + MARKER + "\n"),
    Edit("src/pbrt/wavefront/surfscatter.cpp",
         "#include <pbrt/wavefront/integrator.h>\n",
         "#include <pbrt/wavefront/integrator.h>\n" + _INC),
    Edit("src/pbrt/wavefront/surfscatter.cpp",
         "            if (lambda.SecondaryTerminated())\n"
         "                pixelSampleState.lambda[w.pixelIndex] = lambda;\n",
         "            if (SecondaryWavelengthsTerminated(lambda))  // " + MARKER + "\n"
         "                pixelSampleState.lambda[w.pixelIndex] = lambda;\n"),
]
