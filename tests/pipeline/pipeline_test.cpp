// The pipeline (pipeline/pipeline.h): what every command and test loads and runs
// through. If these fail, `run`, `sweep` and `test` resolve a different run than the
// model and the options say, or report mistakes without their code and source line.
#include "pipeline/pipeline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "lang/diagnostics.h"
#include "flat/mechanism.h"
#include "flat/file_name.h"
#include "runtime/program/program.h"
#include "sim/csv.h"
#include "stdlib/stdlib.h"
#include "compiler/compiler.h"

namespace kanesim {
namespace {

const std::string kRoot = KANESIM_SOURCE_DIR;

// A mass on a spring (k/m = 4, so x(t) = x0 cos(2 t)), its experiment annotation given.
std::string Oscillator(const std::string& body = "Body cart(m = 2, I = identity(3) * 0.01);") {
  return "model Osc\n"
         "  World world(g = {0, 0, 0});\n"
         "  Prismatic slider(axis = {1, 0, 0}, q(start = 0.1));\n"
         "  " + body + "\n"
         "  SpringDamper sd(c = 8, d = 0, s_unstretched = 0);\n"
         "equation\n"
         "  connect(world.frame_b, slider.frame_a);\n"
         "  connect(slider.frame_b, cart.frame_a);\n"
         "  connect(world.frame_b, sd.frame_a);\n"
         "  connect(slider.frame_b, sd.frame_b);\n"
         "  annotation(experiment(StopTime = 3, Tolerance = 1e-7, Interval = 0.25));\n"
         "end Osc;\n";
}

pipeline::LoadResult Load(const std::string& text, const pipeline::RunSpec& spec = {},
                          std::vector<std::string> sets = {}) {
  pipeline::LoadOptions o;
  o.sets = std::move(sets);
  return pipeline::LoadModel(pipeline::Source::Text("osc.mech", text), o, spec);
}

TEST(PipelineNames, EveryNameMapsToOneChoiceAndBack) {
  for (const std::string& n : pipeline::IntegratorNames()) {
    rt::Integrator m = rt::Integrator::IDA;
    ASSERT_TRUE(pipeline::IntegratorFromName(n, &m)) << n;
    EXPECT_EQ(pipeline::IntegratorOptionName(m), n);
  }
  rt::Integrator m = rt::Integrator::IDA;
  ASSERT_TRUE(pipeline::IntegratorFromName("cvode", &m));
  EXPECT_EQ(m, rt::Integrator::CvodeAdams);  // docs/integrators.md: plain cvode is Adams
  ASSERT_TRUE(pipeline::IntegratorFromName("auto", &m));
  EXPECT_EQ(m, rt::Integrator::Auto);
  EXPECT_FALSE(pipeline::IntegratorFromName("rk4", &m));
  rt::SolverPath s = rt::SolverPath::Auto;
  EXPECT_FALSE(pipeline::SolverFromName("fast", &s));
  ASSERT_TRUE(pipeline::SolverFromName("recursive", &s));
  EXPECT_EQ(s, rt::SolverPath::Recursive);
  EXPECT_EQ(pipeline::SolverNames().size(), 4u);
}

// One integrator enum in every layer (issue 39): each --integrator name reaches the compile
// options, the Program's choice and the run as the same rt::Integrator, CVODE's BDF included
// (it was CVODE in the compiler's enum plus a bool in the run's options). If this fails, a
// name maps to a different method in one layer than in another.
TEST(PipelineNames, TheIntegratorIsOneChoiceFromNameToRun) {
  for (const std::string& name : pipeline::IntegratorNames()) {
    pipeline::RunSpec spec;
    ASSERT_TRUE(pipeline::IntegratorFromName(name, &spec.integrator)) << name;
    pipeline::LoadResult r = Load(Oscillator(), spec);
    ASSERT_TRUE(r.model && r.model->program) << r.diagnostics;
    pipeline::ResolvedRun run;
    ASSERT_EQ(pipeline::ResolveRun(*r.model, spec, &run), "");
    EXPECT_EQ(pipeline::CompileOptionsFor(spec).integrator, spec.integrator) << name;
    EXPECT_EQ(run.sim.integrator, spec.integrator) << name;
    const rt::Integrator chosen = rt::Summarize(*r.model->program).integrator;
    if (spec.integrator == rt::Integrator::Auto)
      EXPECT_NE(chosen, rt::Integrator::Auto) << "the compiler resolves auto";
    else
      EXPECT_EQ(chosen, spec.integrator) << name;
  }
}

TEST(PipelineResolve, UnsetValuesComeFromTheExperimentGivenOnesWin) {
  pipeline::LoadResult r = Load(Oscillator());
  ASSERT_TRUE(r.model) << r.diagnostics;
  pipeline::ResolvedRun run;
  ASSERT_EQ(pipeline::ResolveRun(*r.model, {}, &run), "");
  EXPECT_EQ(run.grid.start, 0.0);
  EXPECT_EQ(run.grid.stop, 3.0);
  EXPECT_EQ(run.grid.interval, 0.25);
  EXPECT_EQ(run.sim.rtol, 1e-7);
  EXPECT_EQ(run.sim.atol, 1e-7);  // atol = rtol
  EXPECT_TRUE(run.sim.signals.empty());

  pipeline::RunSpec spec;
  spec.stop_time = 2;
  spec.rtol = 1e-9;
  spec.outputs = {"slider.*"};
  spec.integrator = rt::Integrator::CvodeBdf;
  ASSERT_EQ(pipeline::ResolveRun(*r.model, spec, &run), "");
  EXPECT_EQ(run.grid.stop, 2.0);
  EXPECT_EQ(run.sim.rtol, 1e-9);
  EXPECT_EQ(run.sim.atol, 1e-9);
  EXPECT_EQ(run.sim.integrator, rt::Integrator::CvodeBdf);
  EXPECT_FALSE(run.sim.signals.empty());
  for (const std::string& s : run.sim.signals) EXPECT_EQ(s.rfind("slider.", 0), 0u) << s;
}

TEST(PipelineResolve, EachMistakeIsClassified) {
  pipeline::LoadResult r = Load(Oscillator());
  ASSERT_TRUE(r.model) << r.diagnostics;
  pipeline::ResolvedRun run;
  pipeline::RunProblem p = pipeline::RunProblem::kNone;
  pipeline::RunSpec bad_tol;
  bad_tol.atol = -1;
  EXPECT_NE(pipeline::ResolveRun(*r.model, bad_tol, &run, &p).find("atol"), std::string::npos);
  EXPECT_EQ(p, pipeline::RunProblem::kValue);
  pipeline::RunSpec bad_signal;
  bad_signal.outputs = {"nosuch.q"};
  EXPECT_NE(pipeline::ResolveRun(*r.model, bad_signal, &run, &p), "");
  EXPECT_EQ(p, pipeline::RunProblem::kSignals);
  pipeline::RunSpec backwards;
  backwards.start_time = 5;  // after the experiment's StopTime = 3
  EXPECT_NE(pipeline::ResolveRun(*r.model, backwards, &run, &p), "");
  EXPECT_EQ(p, pipeline::RunProblem::kGrid);
  sim::MemorySink sink;
  EXPECT_EQ(pipeline::Run(*r.model, backwards, sink).status, sim::SimResult::Status::kUsageError);
}

// The run through the pipeline follows x(t) = x0 cos(2 t) (k/m = 8/2), with the forced
// integrator, and writes the experiment's grid.
TEST(PipelineRun, MatchesTheClosedFormWithTheIntegratorAsked) {
  for (const std::string& name : pipeline::IntegratorNames()) {
    pipeline::RunSpec spec;
    ASSERT_TRUE(pipeline::IntegratorFromName(name, &spec.integrator));
    spec.outputs = {"slider.q"};
    pipeline::LoadResult r = Load(Oscillator(), spec);
    ASSERT_TRUE(r.model) << r.diagnostics;
    sim::MemorySink sink;
    sim::SimResult result = pipeline::Run(*r.model, spec, sink);
    ASSERT_EQ(result.status, sim::SimResult::Status::kOk) << name << ": " << result.message;
    if (spec.integrator != rt::Integrator::Auto) {
      EXPECT_EQ(result.stats.method, spec.integrator) << name;
    }
    ASSERT_EQ(sink.times.size(), 13u) << name;  // 0, 0.25, ..., 3
    constexpr double kTol = 1e-5;  // rtol 1e-7 over 1 period, amplitude 0.1: far inside
    for (size_t k = 0; k < sink.times.size(); ++k)
      EXPECT_NEAR(sink.rows[k][0], 0.1 * std::cos(2 * sink.times[k]), kTol) << name << " t=" << sink.times[k];
  }
}

TEST(PipelineLoad, SetValuesApplyAndBadOnesAreE210) {
  pipeline::LoadResult ok = Load(Oscillator("parameter Real mm = 1; Body cart(m = mm, I = identity(3) * 0.01);"),
                                 {}, {"mm=2"});
  ASSERT_TRUE(ok.model) << ok.diagnostics;
  EXPECT_EQ(ok.model->mech->params[static_cast<size_t>(ok.model->mech->FindParam("mm"))].value, 2.0);
  pipeline::LoadResult bad = Load(Oscillator(), {}, {"mm"});
  EXPECT_FALSE(bad.model);
  EXPECT_NE(bad.diagnostics.find("error[E210]"), std::string::npos) << bad.diagnostics;
}

TEST(PipelineLoad, LanguageAndCompilerErrorsAreRenderedWithTheirLine) {
  pipeline::LoadResult lang_error = Load(Oscillator("Bdy cart(m = 2);"));
  EXPECT_FALSE(lang_error.model);
  EXPECT_NE(lang_error.diagnostics.find("osc.mech:4:3: error[E202]"), std::string::npos) << lang_error.diagnostics;
  EXPECT_NE(lang_error.diagnostics.find("1 error\n"), std::string::npos) << lang_error.diagnostics;
  // The triangle inequality broken (0.1 + 0.1 < 1): the compiler's K308, at the body's name, with
  // the source line and a caret like a language diagnostic.
  pipeline::LoadResult compile_error = Load(Oscillator("Body cart(m = 2, I = diagonal({0.1, 0.1, 1}));"));
  EXPECT_FALSE(compile_error.model);
  EXPECT_NE(compile_error.diagnostics.find("osc.mech:4:8: error[K308]"), std::string::npos)
      << compile_error.diagnostics;
  EXPECT_NE(compile_error.diagnostics.find("Body cart(m = 2, I = diagonal"), std::string::npos)
      << compile_error.diagnostics;
  EXPECT_NE(compile_error.diagnostics.find("^"), std::string::npos) << compile_error.diagnostics;
}

TEST(PipelineLoad, CompileFalseStopsAtTheFlatMechanism) {
  pipeline::LoadOptions o;
  o.compile = false;
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/chain.mech"), o, {});
  ASSERT_TRUE(r.model) << r.diagnostics;
  EXPECT_FALSE(r.model->program);
  EXPECT_FALSE(r.model->mech->joints.empty());
}

// The program shares the model's mechanism (no copy), and Rebind keeps sharing it.
TEST(PipelineLoad, TheProgramSharesTheModelsMechanism) {
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/chain.mech"), {}, {});
  ASSERT_TRUE(r.model && r.model->program) << r.diagnostics;
  EXPECT_EQ(r.model->program->mech.get(), r.model->mech.get());
  rt::CompileResult again = rt::Rebind(*r.model->program, r.model->program->param_values);
  ASSERT_TRUE(again.program);
  EXPECT_EQ(again.program->mech.get(), r.model->mech.get());
  // The copying form still gives the program a mechanism of its own.
  rt::CompileResult copied = rt::Compile(*r.model->mech, {});
  ASSERT_TRUE(copied.program);
  EXPECT_NE(copied.program->mech.get(), r.model->mech.get());
  EXPECT_EQ(copied.program->mech->params.size(), r.model->mech->params.size());
}

// The values the elaborator left in the parameters are what evaluating every binding again
// gives, bit for bit (the compile stage of LoadModel takes them instead of evaluating them
// twice): for examples, the chain, UR5's URDF, and --set values read by other bindings. If this
// fails, a model loaded by the pipeline runs with other parameter values than the same
// mechanism compiled by rt::Compile.
TEST(PipelineLoad, ElaboratedParameterValuesAreTheEvaluatedOnes) {
  std::vector<std::pair<pipeline::Source, std::vector<std::string>>> models;
  for (const char* name : {"chain", "double_pendulum", "slider_crank", "fourbar", "spring_mass"})
    models.push_back({pipeline::Source::File(kRoot + "/examples/" + name + ".mech"), {}});
  models.push_back({pipeline::Source::File(kRoot + "/examples/chain.mech"), {"N=25", "L=0.25", "m=3"}});
  models.push_back({pipeline::Source::Text("osc.mech", Oscillator()), {"cart.m=5"}});
  models.push_back({pipeline::Source::File(kRoot + "/tests/import/data/ur5_robot.urdf"), {}});
  size_t compared = 0;
  for (auto& [source, sets] : models) {
    pipeline::LoadOptions o;
    o.sets = sets;
    pipeline::LoadResult r = pipeline::LoadModel(source, o, {});
    ASSERT_TRUE(r.model) << source.path << "\n" << r.diagnostics;
    const std::vector<double> evaluated = flat::EvaluateParams(*r.model->mech);
    const std::vector<double> elaborated = flat::ElaboratedParamValues(*r.model->mech);
    ASSERT_EQ(elaborated.size(), evaluated.size()) << source.path;
    for (size_t i = 0; i < evaluated.size(); ++i)
      EXPECT_EQ(std::memcmp(&elaborated[i], &evaluated[i], sizeof(double)), 0)
          << source.path << " " << r.model->mech->ParamName(i) << ": " << elaborated[i] << " vs " << evaluated[i];
    ASSERT_TRUE(r.model->program) << r.diagnostics;
    EXPECT_EQ(std::memcmp(r.model->program->param_values.data(), evaluated.data(), evaluated.size() * sizeof(double)), 0)
        << source.path;
    compared += evaluated.size();
  }
  EXPECT_GT(compared, 1000u);  // the chain alone has thousands
}

// Values for the parameters given to Compile are counted as Rebind's are.
TEST(PipelineLoad, CompileWithValuesRefusesAWrongCount) {
  pipeline::LoadOptions o;
  o.compile = false;
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/chain.mech"), o, {});
  ASSERT_TRUE(r.model) << r.diagnostics;
  std::vector<double> values = flat::ElaboratedParamValues(*r.model->mech);
  values.pop_back();
  rt::CompileResult c = rt::Compile(r.model->mech, values, {});
  EXPECT_FALSE(c.program);
  ASSERT_EQ(c.errors.size(), 1u);
  EXPECT_NE(c.errors[0].message.find("parameter values for"), std::string::npos) << c.errors[0].message;
}

// File names are interned: equal names are one entry (from any thread), different names
// are not, "" is empty, and a location reads back the name it was given.
TEST(FlatFileName, EqualNamesShareOneEntry) {
  const std::string parts = std::string("<stdlib>/") + "Parts.mech";
  flat::FileName a(parts), b("<stdlib>/Parts.mech"), c("<stdlib>/Joints.mech"), none(""), unset;
  EXPECT_EQ(&a.str(), &b.str());
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == c);
  EXPECT_EQ(a.str(), "<stdlib>/Parts.mech");
  EXPECT_TRUE(a == parts);
  EXPECT_TRUE(none.empty() && unset.empty() && none == unset && none.str().empty());
  EXPECT_FALSE(a.empty());
  std::vector<const std::string*> seen(4);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < seen.size(); ++t)
    threads.emplace_back([&seen, t] {
      for (int i = 0; i < 100; ++i) flat::FileName("thread" + std::to_string(i) + ".mech");
      seen[t] = &flat::FileName("thread7.mech").str();
    });
  for (std::thread& th : threads) th.join();
  for (const std::string* s : seen) EXPECT_EQ(s, &flat::FileName("thread7.mech").str());
  // The locations of two loads of one file name the same entries.
  pipeline::LoadOptions o;
  o.compile = false;
  pipeline::LoadResult r1 = pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/chain.mech"), o, {});
  pipeline::LoadResult r2 = pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/chain.mech"), o, {});
  ASSERT_TRUE(r1.model && r2.model);
  const int i = r1.model->mech->FindParam("N");
  ASSERT_GE(i, 0);
  const flat::SourceLoc& l1 = r1.model->mech->params[static_cast<size_t>(i)].loc;
  const flat::SourceLoc& l2 = r2.model->mech->params[static_cast<size_t>(r2.model->mech->FindParam("N"))].loc;
  EXPECT_EQ(l1.file.str(), kRoot + "/examples/chain.mech");
  EXPECT_EQ(&l1.file.str(), &l2.file.str());
  EXPECT_GT(l1.line, 0);
}

// LoadOptions::data_files (what an FMU gives): the meshes a model names are read from where
// the map says, under the names the model gives them, and a name the map lacks is an error
// even where the file exists.
TEST(Pipeline, DataFilesAreReadWhereTheMapSaysAndOnlyThere) {
  std::ifstream f(kRoot + "/examples/slider_crank_meshes.mech");
  std::stringstream text;
  text << f.rdbuf();
  const pipeline::Source away = pipeline::Source::Text("/nonexistent/sc.mech", text.str());
  pipeline::LoadResult none = pipeline::LoadModel(away, {}, {});
  ASSERT_FALSE(none.model);  // the paths the model names do not exist
  EXPECT_NE(none.diagnostics.find("mesh file not found: /nonexistent/meshes/crank.stl"), std::string::npos);

  std::map<std::string, std::string> files;
  for (const char* part : {"crank", "rod", "slider"})
    files[std::string("/nonexistent/meshes/") + part + ".stl"] = kRoot + "/examples/meshes/" + part + ".stl";
  pipeline::LoadOptions o;
  o.data_files = &files;
  pipeline::LoadResult mapped = pipeline::LoadModel(away, o, {});
  ASSERT_TRUE(mapped.model) << mapped.diagnostics;
  pipeline::LoadResult direct =
      pipeline::LoadModel(pipeline::Source::File(kRoot + "/examples/slider_crank_meshes.mech"), {}, {});
  ASSERT_TRUE(direct.model) << direct.diagnostics;
  EXPECT_EQ(mapped.model->program->param_values, direct.model->program->param_values);  // the same masses
  EXPECT_EQ(mapped.model->mech->data_files.front(), "/nonexistent/meshes/crank.stl");

  files.erase("/nonexistent/meshes/rod.stl");
  pipeline::LoadResult lacking = pipeline::LoadModel(away, o, {});
  ASSERT_FALSE(lacking.model);
  EXPECT_NE(lacking.diagnostics.find("not among the files given with the model: /nonexistent/meshes/rod.stl"),
            std::string::npos);
  // Not read from the named path even where it exists: the example's own folder.
  const pipeline::Source here = pipeline::Source::Text(kRoot + "/examples/sc.mech", text.str());
  std::map<std::string, std::string> empty;
  o.data_files = &empty;
  EXPECT_FALSE(pipeline::LoadModel(here, o, {}).model);
  EXPECT_TRUE(pipeline::LoadModel(here, {}, {}).model);
}

}  // namespace
}  // namespace kanesim
