// The parameter tables (core/solver_param_table.def, ros/node/node_param_table.def) against
// everything that names the parameters: SolverParams' and NodeSettings' defaults, the core's
// enum names, config/default.yaml, the generated dynamic_reconfigure config (from
// cfg/ContactSolver.cfg), the service overrides and the README's Parameters section.
#include "lcp_contact_solver/core/solver_param_table.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/params_file.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <boost/any.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace lcs = ::lcp_contact_solver;
using lcp_contact_solver_ros::defaultSolverParams;

namespace {

using Config = lcp_contact_solver::ContactSolverConfig;

// The node's own table (ros/node/node_param_table.def), as data for the checks below.
struct NodeSpec {
  std::string name, type;  // type: double, int, bool, vec3, enum
  bool in_config;          // group SOFA or NODE
  double def = 0.0, min = 0.0, max = 0.0;
  std::string def_text, doc;
  std::string value;  // NodeSettings{}'s value as text (vec3: its x)
};

std::string numberText(double v) { return lcs::core::exactDoubleText(v); }

std::string axisDoc(std::string doc, char axis) {
  return doc.replace(doc.find("AXIS"), 4, std::string(1, axis));
}

std::vector<NodeSpec> nodeSpecs() {
  const lcp_contact_solver_ros::NodeSettings s;
  constexpr bool SOFA = true, NODE = true, STARTUP = false;
  std::vector<NodeSpec> specs;
#define LCS_NODE_DOUBLE(name, member, d, lo, hi, group, doc) \
  specs.push_back({#name, "double", group, d, lo, hi, numberText(d), doc, numberText(s.member)});
#define LCS_NODE_INT(name, member, d, lo, hi, group, doc) \
  specs.push_back({#name, "int", group, d, lo, hi, std::to_string(d), doc, std::to_string(s.member)});
#define LCS_NODE_BOOL(name, member, d, group, doc) \
  specs.push_back(                                 \
      {#name, "bool", group, 0.0, 0.0, 0.0, d ? "true" : "false", doc, s.member ? "true" : "false"});
#define LCS_NODE_VEC3(name, member, d, lo, hi, group, doc)                                         \
  for (int i = 0; i < 3; ++i)                                                                      \
    specs.push_back({std::string(#name) + "_" + "xyz"[i], "vec3", group, d, lo, hi, numberText(d), \
                     axisDoc(doc, "xyz"[i]), numberText(s.member[i])});
#define LCS_NODE_ENUM(name, member, d, group, doc) \
  specs.push_back(                                 \
      {#name, "enum", group, 0.0, 0.0, 0.0, d, doc, lcp_contact_solver_ros::overloadPolicyName(s.member)});
#include "lcp_contact_solver/ros/node/node_param_table.def"
#undef LCS_NODE_DOUBLE
#undef LCS_NODE_INT
#undef LCS_NODE_BOOL
#undef LCS_NODE_VEC3
#undef LCS_NODE_ENUM
  (void)SOFA, (void)NODE, (void)STARTUP;
  return specs;
}

const NodeSpec* findNodeSpec(const std::string& name) {
  static const std::vector<NodeSpec> specs = nodeSpecs();
  for (const NodeSpec& spec : specs)
    if (spec.name == name) return &spec;
  return nullptr;
}

double configNumber(const Config& config, const std::string& name) {
  for (const auto& description : Config::__getParamDescriptions__()) {
    if (description->name != name) continue;
    boost::any value;
    description->getValue(config, value);
    if (const double* v = boost::any_cast<double>(&value)) return *v;
    if (const int* v = boost::any_cast<int>(&value)) return *v;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::string configText(const Config& config, const std::string& name) {
  for (const auto& description : Config::__getParamDescriptions__()) {
    if (description->name != name) continue;
    boost::any value;
    description->getValue(config, value);
    if (const double* v = boost::any_cast<double>(&value)) return lcs::core::exactDoubleText(*v);
    if (const int* v = boost::any_cast<int>(&value)) return std::to_string(*v);
    if (const bool* v = boost::any_cast<bool>(&value)) return *v ? "true" : "false";
    if (const std::string* v = boost::any_cast<std::string>(&value)) return *v;
  }
  return "<missing>";
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST(ParamTable, DefaultsAreSolverParamsDefaults) {
  const lcs::core::SolverParams defaults;
  ASSERT_FALSE(lcs::core::solverParamSpecs().empty());
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    EXPECT_EQ(lcs::core::paramText(defaults, spec.name), spec.default_text) << spec.name;
}

TEST(ParamTable, EnumChoicesAreTheCoresNames) {
  EXPECT_EQ(lcs::core::findSolverParam("solver")->choices, lcs::core::solverNames());
  EXPECT_EQ(lcs::core::findSolverParam("friction_model")->choices, lcs::core::frictionModelNames());
  EXPECT_EQ(lcs::core::findSolverParam("stopping_rule")->choices,
            (std::vector<std::string>{"residual", "sofa"}));
  EXPECT_EQ(lcs::core::findSolverParam("constraint_level")->choices,
            (std::vector<std::string>{"position", "velocity"}));
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    if (spec.type != lcs::core::ParamType::kEnum) continue;
    for (const std::string& choice : spec.choices) {
      lcs::core::SolverParams p;
      EXPECT_EQ(lcs::core::setParam(&p, spec.name, choice), "") << spec.name;
      EXPECT_EQ(lcs::core::paramText(p, spec.name), choice);
    }
  }
}

// Every parameter away from its default (EveryParameterRoundTripsThroughText checks that).
lcs::core::SolverParams changedParams() {
  lcs::core::SolverParams p;
  for (const char* a : {"tolerance=1e-7",
                        "maxIt=77",
                        "mu=0.1",
                        "initial_guess=false",
                        "build_lcp=false",
                        "regularizationTerm=3e-9",
                        "minW=1e-12",
                        "maxF=250",
                        "computeConstraintForces=true",
                        "displayDebug=true",
                        "solver=prox",
                        "friction_model=pyramid8",
                        "sor=1.3",
                        "time_budget=0.25",
                        "stopping_rule=sofa",
                        "erp=0.2",
                        "softness=1e-6",
                        "constraint_level=velocity",
                        "time_step=0.01",
                        "max_rows=12",
                        "islands=false",
                        "threads=3"})
    EXPECT_EQ(lcs::core::applyAssignment(&p, a), "") << a;
  return p;
}

TEST(ParamTable, EveryParameterRoundTripsThroughText) {
  const lcs::core::SolverParams p = changedParams();
  // Every parameter was changed from its default, so the list above is the whole table.
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    EXPECT_NE(lcs::core::paramText(p, spec.name), spec.default_text) << spec.name << " not covered";
    lcs::core::SolverParams q;
    ASSERT_EQ(lcs::core::setParam(&q, spec.name, lcs::core::paramText(p, spec.name)), "") << spec.name;
    EXPECT_EQ(lcs::core::paramText(q, spec.name), lcs::core::paramText(p, spec.name));
  }
  EXPECT_EQ(p.regularizationTerm, 3e-9);
  EXPECT_EQ(p.threads, 3);
  for (double v : {0.1, 1.0 / 3.0, 1e-300, 6.02214076e23, -2.5})
    EXPECT_EQ(std::strtod(lcs::core::exactDoubleText(v).c_str(), nullptr), v);
}

TEST(ParamTable, OneParserPerTypeRefusesWithTheExpectation) {
  lcs::core::SolverParams p;
  EXPECT_EQ(lcs::core::setParam(&p, "tolerance", "nan"), "tolerance='nan' must be a finite number");
  EXPECT_NE(lcs::core::setParam(&p, "mu", "inf"), "");
  EXPECT_NE(lcs::core::setParam(&p, "mu", "1e400"), "");
  EXPECT_NE(lcs::core::setParam(&p, "mu", " 1"), "");
  EXPECT_NE(lcs::core::setParam(&p, "mu", ""), "");
  EXPECT_EQ(lcs::core::setParam(&p, "maxIt", "5.5"), "maxIt='5.5' must be an integer");
  EXPECT_NE(lcs::core::setParam(&p, "maxIt", "99999999999"), "");
  EXPECT_EQ(lcs::core::setParam(&p, "islands", "maybe"), "islands='maybe' must be true or false");
  EXPECT_EQ(lcs::core::setParam(&p, "solver", "fast"),
            "solver='fast' must be one of auto, pgs, nlgs, lemke, apgd, newton, prox");
  EXPECT_EQ(lcs::core::setParam(&p, "speed", "3"), "'speed' is not a solver parameter");
  EXPECT_EQ(lcs::core::applyAssignment(&p, "tolerance"), "'tolerance' is not of the form name=value");
  EXPECT_EQ(lcs::core::applyAssignment(&p, "initial_guess=false", lcs::core::kParamOverride),
            "'initial_guess' is not a solver parameter");
  const lcs::core::SolverParams defaults;
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())  // refusals changed nothing
    EXPECT_EQ(lcs::core::paramText(p, spec.name), spec.default_text) << spec.name;
  for (const char* yes : {"true", "1", "yes", "On", "TRUE"}) {
    p.islands = false;
    EXPECT_EQ(lcs::core::setParam(&p, "islands", yes), "");
    EXPECT_TRUE(p.islands) << yes;
  }
  EXPECT_EQ(lcs::core::setParam(&p, "islands", "off"), "");
  EXPECT_FALSE(p.islands);
  // Ranges are dynamic_reconfigure's; what a value must be is validateParams' (a start-up
  // tolerance of 1e-300, below the slider's 1e-16, is a test's way to never converge).
  EXPECT_EQ(lcs::core::setParam(&p, "tolerance", "1e-300"), "");
  EXPECT_EQ(p.tolerance, 1e-300);
}

TEST(ParamTable, ShippedDefaultYamlHoldsEveryParameterAtTheNodeDefault) {
  const std::string path = LCS_CONFIG_DIR "/default.yaml";
  lcs::core::SolverParams loaded = defaultSolverParams();
  ASSERT_EQ(lcp_contact_solver_ros::loadParamsFile(path, &loaded), "");  // every key known
  const YAML::Node root = YAML::LoadFile(path);
  const lcs::core::SolverParams node = defaultSolverParams();
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    ASSERT_TRUE(root[spec.name]) << spec.name << " missing from default.yaml";
    lcs::core::SolverParams p;
    ASSERT_EQ(lcs::core::setParam(&p, spec.name, root[spec.name].Scalar()), "");
    EXPECT_EQ(lcs::core::paramText(p, spec.name), lcs::core::paramText(node, spec.name)) << spec.name;
  }
  EXPECT_EQ(node.max_rows, 30000);  // node_param_defaults.def
  for (const auto& entry : root) {  // every key is in one of the two tables
    const std::string key = entry.first.Scalar();
    const NodeSpec* spec = findNodeSpec(entry.second.IsSequence() ? key + "_x" : key);
    EXPECT_TRUE(lcs::core::findSolverParam(key) != nullptr || spec != nullptr) << key << " is in no table";
    if (spec == nullptr) continue;
    if (spec->type == "vec3") {
      ASSERT_EQ(entry.second.size(), 3u) << key;
      for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(entry.second[i].as<double>(), spec->def) << key;
    } else if (spec->type == "double" || spec->type == "int") {
      EXPECT_EQ(entry.second.as<double>(), spec->def) << key;
    } else {
      EXPECT_EQ(entry.second.Scalar(), spec->def_text) << key;
    }
  }
  for (const NodeSpec& spec : nodeSpecs())
    EXPECT_TRUE(root[spec.name] || (spec.type == "vec3" && root[spec.name.substr(0, spec.name.size() - 2)]))
        << spec.name << " missing from default.yaml";
}

TEST(ParamTable, GeneratedReconfigureConfigIsTheTable) {
  const Config& lo = Config::__getMin__();
  const Config& hi = Config::__getMax__();
  const Config& def = Config::__getDefault__();
  const lcs::core::SolverParams node = defaultSolverParams();
  std::set<std::string> in_config;
  for (const auto& description : Config::__getParamDescriptions__()) {
    in_config.insert(description->name);
    const lcs::core::ParamSpec* spec = lcs::core::findSolverParam(description->name);
    if (spec == nullptr) {
      const NodeSpec* node_spec = findNodeSpec(description->name);
      ASSERT_NE(node_spec, nullptr) << description->name << " is in no table";
      EXPECT_TRUE(node_spec->in_config) << node_spec->name;
      EXPECT_EQ(description->description, node_spec->doc) << node_spec->name;
      EXPECT_EQ(configText(def, node_spec->name),
                node_spec->type == "bool" ? node_spec->def_text : numberText(node_spec->def));
      if (node_spec->type != "bool") {
        EXPECT_EQ(configNumber(lo, node_spec->name), node_spec->min) << node_spec->name;
        EXPECT_EQ(configNumber(hi, node_spec->name), node_spec->max) << node_spec->name;
      }
      continue;
    }
    EXPECT_TRUE(spec->access & lcs::core::kParamReconfigure) << spec->name;
    EXPECT_EQ(description->description, spec->doc) << spec->name;
    EXPECT_EQ(configText(def, spec->name), lcs::core::paramText(node, spec->name)) << spec->name;
    if (spec->type == lcs::core::ParamType::kDouble || spec->type == lcs::core::ParamType::kInt) {
      EXPECT_EQ(configNumber(lo, spec->name), spec->min) << spec->name;
      EXPECT_EQ(configNumber(hi, spec->name), spec->max) << spec->name;
    }
    if (spec->type == lcs::core::ParamType::kEnum) {
      for (const std::string& choice : spec->choices)
        EXPECT_NE(description->edit_method.find("'value': '" + choice + "'"), std::string::npos) << choice;
    }
  }
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    EXPECT_EQ(in_config.count(spec.name), (spec.access & lcs::core::kParamReconfigure) ? 1u : 0u)
        << spec.name;
  for (const NodeSpec& spec : nodeSpecs())
    EXPECT_EQ(in_config.count(spec.name), spec.in_config ? 1u : 0u) << spec.name;
}

TEST(ParamTable, NodeSettingsDefaultsAreTheNodeTable) {
  for (const NodeSpec& spec : nodeSpecs()) EXPECT_EQ(spec.value, spec.def_text) << spec.name;
}

TEST(ParamTable, ConfigRoundTripCarriesEveryReconfigurableParameter) {
  lcp_contact_solver_ros::NodeSettings s;
  s.solver = changedParams();
  s.display.showTranslation = {{1.0, -2.0, 3.5}};
  s.display.force_arrow_scale = 0.5;
  s.display.show_w_heatmap = false;
  s.display.showCellWidth = 0.25;
  lcp_contact_solver_ros::NodeSettings t;
  ASSERT_EQ(lcp_contact_solver_ros::fromConfig(lcp_contact_solver_ros::toConfig(s), &t), "");
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    const lcs::core::SolverParams& expected =
        (spec.access & lcs::core::kParamReconfigure) ? s.solver : t.solver;
    EXPECT_EQ(lcs::core::paramText(t.solver, spec.name), lcs::core::paramText(expected, spec.name))
        << spec.name;
  }
  EXPECT_EQ(t.solver.islands, lcp_contact_solver_ros::NodeSettings().solver.islands);  // start-up only: kept
  EXPECT_EQ(t.display.showTranslation, s.display.showTranslation);
  EXPECT_EQ(t.display.force_arrow_scale, 0.5);
  EXPECT_FALSE(t.display.show_w_heatmap);
  EXPECT_EQ(t.display.showCellWidth, 0.25);
}

TEST(ParamTable, ServiceOverridesAreTheTablesOverrideColumn) {
  std::set<std::string> expected;
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    if (spec.access & lcs::core::kParamOverride) expected.insert(spec.name);
  const std::vector<std::string> names = lcp_contact_solver_ros::overridableNames();
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()), expected);
  lcs::core::SolverParams p = defaultSolverParams();
  EXPECT_NE(lcp_contact_solver_ros::applyOverride("initial_guess=false", &p).find("not a solver parameter"),
            std::string::npos);
  EXPECT_EQ(lcp_contact_solver_ros::applyOverride("threads = 2", &p), "");
  EXPECT_EQ(p.threads, 2);
}

// README, "ROS API: contact_solver_node" → "Parameters": one row per parameter with the
// table's type, the node's default and the runtime column; the service paragraph lists
// the override column.
TEST(ParamTable, ReadmeParametersSectionMatchesTheTable) {
  const std::string readme = readText(LCS_SOURCE_DIR "/README.md");
  const std::size_t api = readme.find("## ROS API: `contact_solver_node`");
  ASSERT_NE(api, std::string::npos);
  const std::size_t section = readme.find("### Parameters", api);
  ASSERT_NE(section, std::string::npos);
  const std::size_t end = std::min(readme.find("\n### ", section + 1), readme.find("\n## ", section + 1));
  std::map<std::string, std::vector<std::string>> rows;  // name → cells
  std::istringstream lines(readme.substr(section, end - section));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::size_t from = 1;
    for (std::size_t bar; (bar = line.find(" |", from)) != std::string::npos; from = bar + 2)
      cells.push_back(line.substr(from + 1, bar - from - 1));
    const std::string name = cells[0].substr(1, cells[0].find('`', 1) - 1);
    rows[name] = cells;
  }
  const lcs::core::SolverParams node = defaultSolverParams();
  const std::map<lcs::core::ParamType, std::string> types = {{lcs::core::ParamType::kDouble, "double"},
                                                             {lcs::core::ParamType::kInt, "int"},
                                                             {lcs::core::ParamType::kBool, "bool"},
                                                             {lcs::core::ParamType::kEnum, "string"}};
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    ASSERT_EQ(rows.count(spec.name), 1u) << spec.name << " has no README row";
    const std::vector<std::string>& cells = rows[spec.name];
    ASSERT_GE(cells.size(), 6u) << spec.name;
    EXPECT_EQ(cells[1], types.at(spec.type)) << spec.name;
    const std::string shown = cells[2].substr(0, cells[2].find(' '));
    const std::string value = lcs::core::paramText(node, spec.name);
    if (spec.type == lcs::core::ParamType::kDouble || spec.type == lcs::core::ParamType::kInt) {
      EXPECT_EQ(std::strtod(shown.c_str(), nullptr), std::strtod(value.c_str(), nullptr)) << spec.name;
    } else {
      EXPECT_EQ(shown, value) << spec.name;
    }
    const std::string runtime = (spec.access & lcs::core::kParamReconfigure) ? "yes"
                                : (spec.access & lcs::core::kParamOverride)  ? "no (service: yes)"
                                                                             : "no";
    EXPECT_EQ(cells[4], runtime) << spec.name;
    for (const std::string& choice : spec.choices)
      EXPECT_NE(cells[5].find("`" + choice + "`"), std::string::npos) << spec.name << ": " << choice;
  }
  for (const NodeSpec& spec : nodeSpecs()) {
    if (spec.type == "vec3") continue;  // one row for the three config fields
    ASSERT_EQ(rows.count(spec.name), 1u) << spec.name << " has no README row";
    const std::vector<std::string>& cells = rows[spec.name];
    EXPECT_EQ(cells[1], spec.type == "enum" ? "string" : spec.type) << spec.name;
    const std::string shown = cells[2].substr(0, cells[2].find(' '));
    if (spec.type == "double" || spec.type == "int") {
      EXPECT_EQ(std::strtod(shown.c_str(), nullptr), spec.def) << spec.name;
    } else {
      EXPECT_EQ(shown, spec.def_text) << spec.name;
    }
    EXPECT_EQ(cells[4], spec.in_config ? "yes" : "no") << spec.name;
  }
  // The service paragraph: "`param_overrides` changes ... each as `name=value`: `a`, `b`, ... (e.g."
  const std::string intro = "each as\n`name=value`:";
  const std::size_t list = readme.find(intro, api);
  ASSERT_NE(list, std::string::npos);
  const std::string text =
      readme.substr(list + intro.size(), readme.find("(e.g.", list) - list - intro.size());
  std::set<std::string> listed;
  for (std::size_t a = text.find('`'); a != std::string::npos; a = text.find('`', text.find('`', a + 1) + 1))
    listed.insert(text.substr(a + 1, text.find('`', a + 1) - a - 1));
  const std::vector<std::string> names = lcp_contact_solver_ros::overridableNames();
  EXPECT_EQ(listed, std::set<std::string>(names.begin(), names.end()));
}
