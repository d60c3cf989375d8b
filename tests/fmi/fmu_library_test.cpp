// The FMU's library (kanesim_fmu.so) opened with dlopen as a master opens it, driven through
// its fmi2* functions with hostile calls: in the sanitizer build (CI's ASan + UBSan run) this
// is the FMU under AddressSanitizer, where FMPy (tests/fmi/*.py) cannot load it. Each call
// must return fmi2Error with a message, never crash, leak or read out of bounds.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdarg>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fmi/fmi2_abi.h"
#include "fmi/instance.h"

namespace {

namespace fs = std::filesystem;

const char* const kPendulum = R"(
model P "A pendulum whose joint torque is NaN after t = 0.5"
  parameter Real L(unit = "m") = 1;
  World world;
  Revolute hinge(axis = {0, 0, 1}, q(start = 0.3));
  Rod rod(L = L, m = 1);
  output Real tip = rod.frame_b.r[2];
equation
  connect(world.frame_b, hinge.frame_a);
  connect(hinge.frame_b, rod.frame_a);
  hinge.tau = sqrt(0.5 - time);
end P;
)";

std::vector<std::string> g_messages;
void Logger(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String message, ...) {
  g_messages.push_back(message);
}

// The library's functions by name, and an FMU's resources written beside the test.
class FmuLibrary : public ::testing::Test {
 protected:
  void SetUp() override {
    handle_ = dlopen(KANESIM_FMU_LIBRARY, RTLD_NOW | RTLD_LOCAL);
    ASSERT_NE(handle_, nullptr) << dlerror();
    dir_ = fs::temp_directory_path() / ("kanesim_fmu_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "resources");
    std::ofstream(dir_ / "resources" / "model.mech") << kPendulum;
    kanesim::fmi::FmuSettings settings;
    settings.model = "P";
    settings.guid = "{test}";
    std::ofstream(dir_ / "resources" / "settings.txt") << kanesim::fmi::FormatSettings(settings);
    callbacks_ = {Logger, nullptr, nullptr, nullptr, nullptr};
    g_messages.clear();
  }
  // The library stays open, as a master keeps it: after dlclose, LeakSanitizer would count
  // what the library's statics still point to (flat/file_name.cpp's table) as leaked.
  void TearDown() override { fs::remove_all(dir_); }
  template <class F>
  F Fn(const char* name) {
    void* f = dlsym(handle_, name);
    EXPECT_NE(f, nullptr) << name;
    return reinterpret_cast<F>(f);
  }
  fmi2Component Instantiate(fmi2Type type, const char* guid = "{test}") {
    auto instantiate = Fn<fmi2Component (*)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions*,
                                            fmi2Boolean, fmi2Boolean)>("fmi2Instantiate");
    const std::string uri = "file://" + (dir_ / "resources").string();
    return instantiate("p", type, guid, uri.c_str(), &callbacks_, 0, 0);
  }
  bool Logged(const std::string& text) const {
    for (const std::string& m : g_messages)
      if (m.find(text) != std::string::npos) return true;
    return false;
  }

  void* handle_ = nullptr;
  fs::path dir_;
  fmi2CallbackFunctions callbacks_{};
};

using Simple = fmi2Status (*)(fmi2Component);
using DoStep = fmi2Status (*)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
using SetReal = fmi2Status (*)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
using SetupExperiment = fmi2Status (*)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);

TEST_F(FmuLibrary, OnlyTheStandardsFunctionsAreExported) {
  // A kanesim symbol visible from the FMU could bind another FMU's (or Python's) copy.
  EXPECT_NE(dlsym(handle_, "fmi2DoStep"), nullptr);
  EXPECT_NE(dlsym(handle_, "fmi3DoStep"), nullptr);
  EXPECT_EQ(dlsym(handle_, "_ZN7kanesim8pipeline9LoadModelERKNS0_6SourceERKNS0_11LoadOptionsERKNS0_7RunSpecE"), nullptr);
}

TEST_F(FmuLibrary, AWrongGuidOrResourceLocationIsRefusedWithAMessage) {
  EXPECT_EQ(Instantiate(fmi2CoSimulation, "{other}"), nullptr);
  EXPECT_TRUE(Logged("is not this FMU's"));
  auto instantiate = Fn<fmi2Component (*)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions*,
                                          fmi2Boolean, fmi2Boolean)>("fmi2Instantiate");
  EXPECT_EQ(instantiate("p", fmi2CoSimulation, "{test}", "http://example/x", &callbacks_, 0, 0), nullptr);
  EXPECT_EQ(instantiate("p", fmi2CoSimulation, "{test}", nullptr, &callbacks_, 0, 0), nullptr);
  EXPECT_EQ(instantiate("p", fmi2CoSimulation, "{test}", "file:///x", nullptr, 0, 0), nullptr);
}

TEST_F(FmuLibrary, HostileCallsAndANumericalFailureAreErrorsNotCrashes) {
  fmi2Component c = Instantiate(fmi2CoSimulation);
  ASSERT_NE(c, nullptr);
  auto do_step = Fn<DoStep>("fmi2DoStep");
  auto set_real = Fn<SetReal>("fmi2SetReal");
  const fmi2ValueReference L = 3;  // hinge.q, hinge.u, der x2, tip, then the parameters
  const double nan = std::nan("");
  EXPECT_EQ(do_step(c, 0.0, 0.1, 1), fmi2Error);  // before initialization
  EXPECT_EQ(set_real(c, &L, 1, &nan), fmi2Error);
  EXPECT_EQ(Fn<SetupExperiment>("fmi2SetupExperiment")(c, 1, -1.0, 0.0, 0, 0.0), fmi2Error);
  EXPECT_EQ(Fn<SetupExperiment>("fmi2SetupExperiment")(c, 1, 1e-8, 0.0, 0, 0.0), fmi2OK);
  EXPECT_EQ(Fn<Simple>("fmi2EnterInitializationMode")(c), fmi2OK);
  EXPECT_EQ(Fn<Simple>("fmi2ExitInitializationMode")(c), fmi2OK);
  EXPECT_EQ(do_step(c, 0.0, 0.25, 1), fmi2OK);
  EXPECT_EQ(do_step(c, 0.0, 0.25, 1), fmi2Error);  // backwards
  EXPECT_EQ(do_step(c, 0.25, -1.0, 1), fmi2Error);
  EXPECT_EQ(do_step(c, 0.25, nan, 1), fmi2Error);
  // Directional derivatives: a NaN seed, a known that is no state or input, an unknown that
  // is no derivative or output, a value reference past the end, no place for the result.
  using Directional = fmi2Status (*)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2ValueReference[],
                                     size_t, const fmi2Real[], fmi2Real[]);
  auto directional = Fn<Directional>("fmi2GetDirectionalDerivative");
  const fmi2ValueReference der_u = 3, q = 0, param = 5, far = 1000000;
  double seed = 1.0, out = 0.0;
  EXPECT_EQ(directional(c, &der_u, 1, &q, 1, &nan, &out), fmi2Error);
  EXPECT_EQ(directional(c, &der_u, 1, &param, 1, &seed, &out), fmi2Error);
  EXPECT_EQ(directional(c, &q, 1, &q, 1, &seed, &out), fmi2Error);
  EXPECT_EQ(directional(c, &der_u, 1, &far, 1, &seed, &out), fmi2Error);
  EXPECT_EQ(directional(c, &der_u, 1, &q, 1, nullptr, &out), fmi2Error);
  EXPECT_EQ(directional(c, &der_u, 1, &q, 1, &seed, nullptr), fmi2Error);
  EXPECT_EQ(directional(c, &der_u, 1, &q, 1, &seed, &out), fmi2OK);
  EXPECT_TRUE(std::isfinite(out) && out != 0.0) << out;  // gravity's torque changes with q
  g_messages.clear();
  EXPECT_EQ(do_step(c, 0.25, 0.5, 1), fmi2Error);  // the torque is NaN past t = 0.5
  EXPECT_TRUE(Logged("numerical failure at t = ")) << (g_messages.empty() ? "" : g_messages.back());
  EXPECT_EQ(Fn<Simple>("fmi2Terminate")(c), fmi2OK);
  Fn<void (*)(fmi2Component)>("fmi2FreeInstance")(c);
}

TEST_F(FmuLibrary, AnyBytesGivenAsASerializedStateAreRefusedOrRestored) {
  fmi2Component c = Instantiate(fmi2ModelExchange);
  ASSERT_NE(c, nullptr);
  auto get = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate*)>("fmi2GetFMUstate");
  auto size_of = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate, size_t*)>("fmi2SerializedFMUstateSize");
  auto serialize = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t)>("fmi2SerializeFMUstate");
  auto deserialize = Fn<fmi2Status (*)(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate*)>("fmi2DeSerializeFMUstate");
  auto set = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate)>("fmi2SetFMUstate");
  auto release = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate*)>("fmi2FreeFMUstate");
  fmi2FMUstate state = nullptr;
  ASSERT_EQ(get(c, &state), fmi2OK);
  size_t size = 0;
  ASSERT_EQ(size_of(c, state, &size), fmi2OK);
  std::vector<fmi2Byte> bytes(size);
  ASSERT_EQ(serialize(c, state, bytes.data(), size), fmi2OK);
  EXPECT_EQ(serialize(c, state, bytes.data(), size - 1), fmi2Error);
  // Every truncation, and a flipped count, must be refused without reading past the bytes.
  for (size_t n = 0; n < size; ++n) {
    std::vector<fmi2Byte> cut(bytes.begin(), bytes.begin() + long(n));
    fmi2FMUstate other = nullptr;
    EXPECT_EQ(deserialize(c, cut.data(), n, &other), fmi2Error) << n;
  }
  std::vector<fmi2Byte> bad = bytes;
  bad[6 + 8 + 7] ^= 0x40;  // the state count's exponent
  fmi2FMUstate other = nullptr;
  EXPECT_EQ(deserialize(c, bad.data(), bad.size(), &other), fmi2Error);
  ASSERT_EQ(deserialize(c, bytes.data(), bytes.size(), &other), fmi2OK);
  EXPECT_EQ(set(c, other), fmi2OK);
  EXPECT_EQ(release(c, &other), fmi2OK);
  EXPECT_EQ(release(c, &state), fmi2OK);
  Fn<void (*)(fmi2Component)>("fmi2FreeInstance")(c);
}

// A rod swinging without gravity onto its end stop q_max = 0.5 at speed 1, restitution 0.5.
const char* const kStopped = R"(
model S
  World world(g = {0, 0, 0});
  Revolute hinge(axis = {0, 0, 1}, q(start = 0.3), u(start = 1), q_max = 0.5, restitution = 0.5);
  Rod rod(L = 1, m = 1);
equation
  connect(world.frame_b, hinge.frame_a);
  connect(hinge.frame_b, rod.frame_a);
end S;
)";

TEST_F(FmuLibrary, ModelExchangeEventIndicatorsAndTheImpactInEventMode) {
  // The master's part done by hand: Euler steps past the crossing of the indicator (the
  // gap q_max - q), then event mode, where the impact reverses the speed to -e u. Hostile
  // arguments on the way are errors; under ASan nothing reads out of bounds.
  std::ofstream(dir_ / "resources" / "model.mech") << kStopped;
  kanesim::fmi::FmuSettings settings;
  settings.model = "S";
  settings.guid = "{test}";
  std::ofstream(dir_ / "resources" / "settings.txt") << kanesim::fmi::FormatSettings(settings);
  fmi2Component c = Instantiate(fmi2ModelExchange);
  ASSERT_NE(c, nullptr);
  using Array = fmi2Status (*)(fmi2Component, fmi2Real[], size_t);
  using SetArray = fmi2Status (*)(fmi2Component, const fmi2Real[], size_t);
  auto indicators = Fn<Array>("fmi2GetEventIndicators");
  auto states = Fn<Array>("fmi2GetContinuousStates");
  auto set_states = Fn<SetArray>("fmi2SetContinuousStates");
  auto new_states = Fn<fmi2Status (*)(fmi2Component, fmi2EventInfo*)>("fmi2NewDiscreteStates");
  EXPECT_EQ(Fn<Simple>("fmi2EnterInitializationMode")(c), fmi2OK);
  EXPECT_EQ(Fn<Simple>("fmi2ExitInitializationMode")(c), fmi2OK);
  double z[3] = {0, 0, 0}, y[2] = {0, 0};
  EXPECT_EQ(indicators(c, nullptr, 2), fmi2Error);
  EXPECT_EQ(indicators(c, z, 3), fmi2Error);  // two indicators: the gap, its graze guard
  EXPECT_EQ(new_states(c, nullptr), fmi2Error);
  ASSERT_EQ(indicators(c, z, 2), fmi2OK);
  EXPECT_NEAR(z[0], 0.2, 1e-12);
  EXPECT_NEAR(z[1], 1.0, 1e-12);  // minus the gap's rate: closing at 1 rad/s
  fmi2EventInfo info{};
  ASSERT_EQ(new_states(c, &info), fmi2OK);  // the initial event update: nothing happens
  EXPECT_EQ(info.valuesOfContinuousStatesChanged, 0);
  ASSERT_EQ(Fn<Simple>("fmi2EnterContinuousTimeMode")(c), fmi2OK);
  ASSERT_EQ(states(c, y, 2), fmi2OK);
  y[0] = 0.5 + 1e-9;  // just past the stop, still at speed 1
  ASSERT_EQ(set_states(c, y, 2), fmi2OK);
  ASSERT_EQ(indicators(c, z, 2), fmi2OK);
  EXPECT_LT(z[0], 0.0);
  EXPECT_EQ(new_states(c, &info), fmi2Error);  // only in event mode
  ASSERT_EQ(Fn<Simple>("fmi2EnterEventMode")(c), fmi2OK);
  ASSERT_EQ(new_states(c, &info), fmi2OK);
  EXPECT_EQ(info.valuesOfContinuousStatesChanged, 1);
  ASSERT_EQ(states(c, y, 2), fmi2OK);
  EXPECT_NEAR(y[1], -0.5, 1e-12);  // u after = -e u before
  ASSERT_EQ(new_states(c, &info), fmi2OK);  // a second update at the same instant: no second impact
  EXPECT_EQ(info.valuesOfContinuousStatesChanged, 0);
  // The FMU state after the impact restores it: states, and no impact again at the next update.
  auto get = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate*)>("fmi2GetFMUstate");
  auto set = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate)>("fmi2SetFMUstate");
  auto release = Fn<fmi2Status (*)(fmi2Component, fmi2FMUstate*)>("fmi2FreeFMUstate");
  fmi2FMUstate saved = nullptr;
  ASSERT_EQ(get(c, &saved), fmi2OK);
  const double other[2] = {0.1, 3.0};
  ASSERT_EQ(set_states(c, other, 2), fmi2OK);
  ASSERT_EQ(set(c, saved), fmi2OK);
  double back[2] = {0, 0};
  ASSERT_EQ(states(c, back, 2), fmi2OK);
  EXPECT_EQ(back[0], y[0]);
  EXPECT_EQ(back[1], y[1]);
  ASSERT_EQ(new_states(c, &info), fmi2OK);
  EXPECT_EQ(info.valuesOfContinuousStatesChanged, 0);
  EXPECT_EQ(release(c, &saved), fmi2OK);
  EXPECT_EQ(Fn<Simple>("fmi2Terminate")(c), fmi2OK);
  Fn<void (*)(fmi2Component)>("fmi2FreeInstance")(c);
}

}  // namespace
