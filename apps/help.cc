#include "apps/help.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <limits.h>
#include <unistd.h>

namespace zwidth::app {
namespace {

// One option's topic and, for the completion, the words its value may be.
struct OptionTopic {
  std::string_view command;  // "" = this option in any command
  std::string_view option;   // long name without the dashes
  std::string_view topic;    // one of kHelpTopics
  std::string_view choices;  // words for the completion; "" = a file name or a number
  bool files_too = false;    // besides the choices, a file (--reference table1 | MODEL.json)
};

// A row for (command, option) wins over the row for ("", option).
constexpr OptionTopic kOptionTopics[] = {
    // simulate: the plant's log
    {"simulate", "model", "Simulation", ""},
    {"simulate", "seconds", "Simulation", ""},
    {"simulate", "rate", "Simulation", ""},
    {"simulate", "torque-rms", "Simulation", ""},
    {"simulate", "bandwidth-hz", "Simulation", ""},
    {"simulate", "encoder-step", "Simulation", ""},
    {"simulate", "noise-std", "Simulation", ""},
    {"simulate", "delay-samples", "Simulation", ""},
    {"simulate", "seed", "Simulation", ""},
    // excite: the signal to play on a rig
    {"excite", "kind", "Excitation", "noise multisine chirp"},
    {"excite", "seconds", "Excitation", ""},
    {"excite", "rate", "Excitation", ""},
    {"excite", "rms", "Excitation", ""},
    {"excite", "fmin", "Excitation", ""},
    {"excite", "fmax", "Excitation", ""},
    {"excite", "seed", "Excitation", ""},
    {"excite", "random-phases", "Excitation", ""},
    // which columns or datasets of a log, and how to read them
    {"", "input-column", "Log selection", ""},
    {"", "output-column", "Log selection", ""},
    {"", "time-column", "Log selection", "none"},
    {"", "delimiter", "Log selection", ""},
    {"", "input-scale", "Log selection", ""},
    {"", "output-scale", "Log selection", ""},
    {"", "time-unit", "Log selection", "s ms us"},
    {"", "input-dataset", "Log selection", ""},
    {"", "output-dataset", "Log selection", ""},
    {"", "time-dataset", "Log selection", ""},
    {"", "rate", "Log selection", ""},
    {"", "input-unit", "Log selection", ""},
    {"", "output-unit", "Log selection", ""},
    {"", "counts-per-rev", "Log selection", ""},
    {"", "counts-per-m", "Log selection", ""},
    {"", "decimal-comma", "Log selection", ""},
    // spectra -> frequency response
    {"", "window", "Estimate (Welch)", "hann hamming rect"},
    {"", "window-length", "Estimate (Welch)", ""},
    {"", "overlap", "Estimate (Welch)", ""},
    {"", "detrend", "Estimate (Welch)", "none mean linear"},
    {"", "estimator", "Estimate (Welch)", "h1 h2 lpm lrm robust"},
    {"", "local-half-width", "Estimate (Welch)", ""},
    {"", "local-order", "Estimate (Welch)", ""},
    {"", "local-denominator-order", "Estimate (Welch)", ""},
    {"", "local-differences", "Estimate (Welch)", ""},
    {"", "fmin", "Estimate (Welch)", ""},
    {"", "fmax", "Estimate (Welch)", ""},
    {"", "reference-column", "Estimate (Welch)", ""},
    {"", "reference-dataset", "Estimate (Welch)", ""},
    {"", "whole-record", "Estimate (Welch)", ""},
    {"", "period-samples", "Estimate (Welch)", ""},
    {"", "transient-periods", "Estimate (Welch)", ""},
    // frequency response -> model
    {"", "modes", "Fit", "auto"},
    {"", "max-modes", "Fit", ""},
    {"", "delay-samples", "Fit", "auto"},
    {"", "max-delay", "Fit", ""},
    {"", "allow-short", "Fit", ""},
    {"", "min-input-power", "Fit", ""},
    {"", "min-coherence", "Fit", ""},
    {"", "noise-coherence-sigmas", "Fit", ""},
    {"", "init", "Fit", ""},
    {"", "starts", "Fit", ""},
    {"", "friction", "Fit", "none auto coulomb"},  // fit, run
    {"", "max-iterations", "Fit", ""},
    // the device's nonlinear part: friction, encoder and actuator (simulate, relay, wall, check)
    {"", "coulomb", "Friction and actuator", ""},
    {"", "coulomb-pos", "Friction and actuator", ""},
    {"", "coulomb-neg", "Friction and actuator", ""},
    {"", "friction-offset", "Friction and actuator", ""},
    {"", "breakaway", "Friction and actuator", ""},
    {"", "no-model-friction", "Friction and actuator", ""},
    {"", "torque-saturation", "Friction and actuator", ""},
    {"", "dac-step", "Friction and actuator", ""},
    {"", "encoder-step", "Friction and actuator", ""},
    // a second model to compare with
    {"", "reference", "Comparison", "table1", true},
    {"compare", "table2", "Comparison", ""},
    {"compare", "coulomb-levels", "Comparison", ""},
    {"compare", "amplitude", "Comparison", ""},
    {"compare", "seconds", "Comparison", ""},
    {"run", "table2", "Comparison", ""},
    {"run", "coulomb-levels", "Comparison", ""},
    {"run", "amplitude", "Comparison", ""},
    {"run", "seconds", "Comparison", ""},
    // the haptic loop and its Z-width
    {"", "delays", "Loop and stability", ""},
    {"", "delay", "Loop and stability", ""},
    {"", "damping", "Loop and stability", ""},
    {"", "period", "Loop and stability", ""},
    {"", "b-min", "Loop and stability", ""},
    {"", "b-max", "Loop and stability", ""},
    {"", "b-step", "Loop and stability", ""},
    {"", "b-points", "Loop and stability", ""},
    {"", "velocity-filter-hz", "Loop and stability", ""},
    {"", "velocity-filter-coeffs", "Loop and stability", ""},
    {"", "hand", "Loop and stability", ""},
    {"", "report-filter-hz", "Loop and stability", ""},
    {"check", "model", "Loop and stability", ""},
    {"check", "marginal-sigmas", "Loop and stability", ""},
    {"wall", "stiffness", "Loop and stability", ""},
    {"wall", "seconds", "Loop and stability", ""},
    {"wall", "initial-position", "Loop and stability", ""},
    {"relay", "amplitude", "Loop and stability", ""},
    {"boundary", "amplitude-k-factor", "Loop and stability", ""},
    {"relay", "seconds", "Loop and stability", ""},
    {"filter-sweep", "f-min", "Loop and stability", ""},
    {"filter-sweep", "f-max", "Loop and stability", ""},
    {"filter-sweep", "points", "Loop and stability", ""},
    {"filter-sweep", "measure", "Loop and stability", "kcr-max area"},
    {"filter-sweep", "area-b-max", "Loop and stability", ""},
    // the std of the Z-width
    {"", "monte-carlo", "Uncertainty", ""},
    {"boundary", "seed", "Uncertainty", ""},
    // a model against a fresh log
    {"validate", "max-lag", "Validation", ""},
    // what is written, and where
    {"", "trace", "Output", ""},
    {"", "output", "Output", ""},
    {"", "summary", "Output", ""},
    {"", "coherences-output", "Output", ""},
    {"", "json", "Output", ""},
    {"", "force", "Output", ""},
    {"", "no-figures", "Output", ""},
    {"", "png", "Output", ""},
    {"", "format", "Output", "json hdf5 matlab python statespace mat mat73"},
    {"export", "response", "Output", ""},
    {"", "units", "Output", "rotary linear"},
    // batch: many units, one table
    {"batch", "manifest", "Batch", ""},
    {"batch", "unit-folders", "Batch", ""},
    {"batch", "jobs", "Batch", ""},
    {"batch", "restart", "Batch", ""},
    {"batch", "spec", "Batch", ""},
    {"batch", "population", "Batch", ""},
    {"batch", "fleet-report", "Batch", ""},
    {"batch", "outlier-quantile", "Batch", ""},
};

const OptionTopic* TopicOf(std::string_view command, const CLI::Option& opt) {
  const OptionTopic* any = nullptr;
  for (const std::string& name : opt.get_lnames()) {
    for (const OptionTopic& t : kOptionTopics) {
      if (t.option != name) continue;
      if (t.command == command) return &t;
      if (t.command.empty() && !any) any = &t;
    }
  }
  return any;
}

// An example per command: the command line, then what it does. kDataMark
// stands for the shipped data sets' folder (Table I), DatasetsDir(): the
// examples name files that exist for the binary printing them, installed or
// in the build tree. tests/cli_help_test.sh checks that every path an example
// names exists, and runs every example, in this order, in one folder (each
// uses the files the ones before wrote).
struct Example {
  std::string_view command;
  std::string_view line;
  std::string_view what;
};
constexpr Example kExamples[] = {
    {"excite", "zwidth excite --kind multisine --seconds 10 --rate 1000 --fmin 1 --fmax 200 -o excitation.txt",
     "a Schroeder-phase multisine, 1-200 Hz, to play on the rig"},
    {"simulate", "zwidth simulate --model @DATA@/phantom/table1.json --seconds 30 -o log.h5",
     "30 s of white-noise torque through the paper's PHANToM model (Table I)"},
    {"simulate", "zwidth simulate --model @DATA@/phantom/table1.json --seed 2 -o fresh.h5",
     "another log of the same device (another seed), to validate a fit on"},
    {"estimate", "zwidth estimate log.h5 -o frf.csv", "the frequency response, Welch H1 with a Hann window"},
    {"fit", "zwidth fit log.h5 -o model.json",
     "fit eq. (1): order by BIC, delay from the phase of H / G_rigid (the defaults); prints the verdict"},
    {"fit", "zwidth fit frf.csv --modes 2 -o model2.json", "fit a saved frequency response with two sections"},
    {"compare", "zwidth compare model.json --reference table1",
     "parameters and Z-width at delays 2, 4, 8 against the paper's Table I"},
    {"validate", "zwidth validate model.json fresh.h5",
     "the model on a log it was not fitted to: fit %, residual correlations, misfit in std units, verdict"},
    {"boundary", "zwidth boundary model.json --delays 2,4,8 -o boundary.csv --summary summary.json",
     "the stable K intervals at every B, and B_t, K_CR^max, B_max per delay"},
    {"relay", "zwidth relay model.json --delay 2 --damping 0 --seconds 5",
     "the relay experiment of section IV, simulated at B = 0"},
    {"wall", "zwidth wall model.json --stiffness 2 --damping 0.01 --delay 2 --coulomb 0.008",
     "the virtual wall simulated on the device with 8 mN m of Coulomb friction: decays, limit cycle or grows"},
    {"check", "zwidth check scene.json --model model.json --delay 2",
     "is each object of scene.json ({\"objects\": [{\"name\", \"K\", \"B\"}]}) stable? exit 3 when not"},
    {"export", "zwidth export model.json --format matlab -o model.m", "the model for MATLAB/Octave"},
    {"filter-sweep", "zwidth filter-sweep model.json --delay 2 -o sweep.csv",
     "the velocity low-pass cut-off that maximises K_CR^max"},
    {"run", "zwidth run log.h5 --reference table1 --no-figures -o out",
     "estimate, fit, Z-width, comparison and report.html in out/ (without figures: no gnuplot)"},
    {"batch", "zwidth batch log.h5 fresh.h5 -o fleet.csv",
     "run's estimate, fit and Z-width per log (paths, quoted globs or --manifest units.csv) into one table; "
     "the same command again resumes"},
};

constexpr std::string_view kDataMark = "@DATA@";
constexpr const char* kInstalledDataDir = "/usr/share/zwidth";  // the package's, as the man page's FILES

// The shipped data sets' folder of this executable, found as its plugins are
// (apps/plugins.cc): <bindir>/ZWIDTH_DATA_DIR_FROM_BIN, /usr/share/zwidth
// when installed, build/share/zwidth in the build tree (CMakeLists.txt copies
// Table I and II there). The installed folder when that holds no Table I (an
// executable copied elsewhere) and for the man page, which describes the
// installed package.
std::string DatasetsDir(bool man) {
  if (man) return kInstalledDataDir;
  char exe[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) return kInstalledDataDir;
  std::string dir(exe, static_cast<size_t>(n));
  dir.erase(dir.rfind('/') + 1);
  std::error_code ec;
  const std::filesystem::path data =
      std::filesystem::weakly_canonical(std::filesystem::path(dir + ZWIDTH_DATA_DIR_FROM_BIN), ec);
  if (ec || !std::filesystem::is_regular_file(data / "phantom" / "table1.json", ec)) return kInstalledDataDir;
  return data.string();
}

// man: for help2man, whose "Examples:" line would start the EXAMPLES section
// and whose "$ " prefix sets a line in constant width.
std::string Footer(std::string_view command, bool man = false) {
  std::ostringstream out;
  for (const Example& e : kExamples) {
    if (e.command != command) continue;
    if (out.tellp() == 0) out << (man ? "For example:\n\n" : "Examples:\n");
    std::string line(e.line);
    if (const size_t at = line.find(kDataMark); at != std::string::npos) {
      line.replace(at, kDataMark.size(), DatasetsDir(man));
    }
    out << (man ? "  $ " : "  ") << line << "\n      " << e.what << "\n";
  }
  return out.str();
}

// Prints the option groups in kHelpTopics' order (CLI11 prints them in the
// order of the options' declaration), and each command's footer also in
// --help-all, which CLI11 leaves out of its expanded subcommands. The rest is
// CLI11's Formatter::make_help and make_expanded (2.1), whose make_groups is
// not virtual.
class TopicFormatter : public CLI::Formatter {
 public:
  std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override {
    if (mode == CLI::AppFormatMode::Sub) return make_expanded(app);
    return make_description(app) + make_usage(app, name) + make_positionals(app) + Groups(app, mode) +
           make_subcommands(app, mode) + "\n" + make_footer(app);
  }
  std::string make_expanded(const CLI::App* sub) const override {
    std::string text = make_description(sub) + make_positionals(sub) + Groups(sub, CLI::AppFormatMode::Sub) +
                       make_subcommands(sub, CLI::AppFormatMode::Sub);
    for (size_t i; (i = text.find("\n\n")) != std::string::npos;) text.erase(i, 1);  // no blank lines
    text += sub->get_footer();
    std::string out = sub->get_display_name(true) + "\n";  // the rest indented by two
    for (size_t i = 0; i < text.size(); ++i) {
      if (i == 0 || text[i - 1] == '\n') out += "  ";
      out += text[i];
    }
    return out;
  }

 private:
  // "Options" (help) first, then the topics, then any other group.
  std::string Groups(const CLI::App* app, CLI::AppFormatMode mode) const {
    std::vector<std::string> groups = app->get_groups();
    std::stable_sort(groups.begin(), groups.end(), [](const std::string& a, const std::string& b) {
      return Rank(a) < Rank(b);
    });
    std::string out;
    for (const std::string& group : groups) {
      const std::vector<const CLI::Option*> opts = app->get_options([&](const CLI::Option* o) {
        return o->get_group() == group && o->nonpositional() &&
               (mode != CLI::AppFormatMode::Sub || (o != app->get_help_ptr() && o != app->get_help_all_ptr()));
      });
      if (!group.empty() && !opts.empty()) out += make_group(group, false, opts);
    }
    return out;
  }
  static int Rank(const std::string& group) {
    const auto* begin = std::begin(kHelpTopics);
    const auto* it = std::find(begin, std::end(kHelpTopics), group);
    if (group == "Options") return -1;
    return static_cast<int>(it - begin);
  }
};

std::string Words(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

// Every name of an option: -o --output.
std::vector<std::string> Names(const CLI::Option& o) {
  std::vector<std::string> names;
  for (const std::string& s : o.get_snames()) names.push_back("-" + s);
  for (const std::string& l : o.get_lnames()) names.push_back("--" + l);
  return names;
}

}  // namespace

// Every exit status the program uses (apps/main.cc, ExitStatus in apps/common.h,
// io/atomic_file.cc's signal handlers), for --help and the man page.
constexpr const char* kExitStatusText =
    "0 success; 2 a bad request or a bad file (nothing written); 1 a computation that failed on\n"
    "valid input (nothing written), or an internal error; 3 (check) some object of the scene is unstable;\n"
    "4 (check) none is unstable but some is marginal, (batch) some unit failed (its row says why);\n"
    "128+N killed by signal N (SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ remove the temporary files first).\n";

// The rule of every output (io/atomic_file.h CheckOutputPath, CheckOutputKind, OutputFolder).
constexpr const char* kOutputRuleText =
    "-o FILE: a new name, or an existing file, which is replaced (as cp replaces it; its mode kept).\n"
    "Refused (exit 2, nothing written): a folder, a device, one of the command's inputs, or a name\n"
    "whose extension is another format's than the command writes (boundary -o model.json).\n"
    "run -o DIR: a new or empty folder, or --force to replace its files of the same names.\n";

void OrganizeHelp(CLI::App& app) {
  auto formatter = std::make_shared<TopicFormatter>();
  app.formatter(formatter);
  app.name("zwidth");  // not argv[0]: the usage line reads the same wherever it runs (the man page)
  app.footer(std::string("Examples: in zwidth COMMAND --help; every command's help: zwidth --help-all.\n"
                         "Outputs: ") + kOutputRuleText + "Exit status: " + kExitStatusText);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    sub->formatter(formatter);
    sub->footer(Footer(sub->get_name()));
    for (CLI::Option* o : sub->get_options()) {
      if (!o->nonpositional() || o == sub->get_help_ptr() || o->get_group().empty()) continue;
      if (const OptionTopic* t = TopicOf(sub->get_name(), *o)) o->group(std::string(t->topic));
    }
  }
  app.set_help_all_flag("--help-all", "Print the help of every command and exit");
  app.add_flag_callback("--bash-completion", [&app] {
       std::fputs(BashCompletion(app).c_str(), stdout);
       throw CLI::Success();
     })->group("");  // hidden, as --help-man
  app.add_flag_callback("--help-man", [&app] {
       std::fputs(ManText(app).c_str(), stdout);
       throw CLI::Success();
     })->group("");
}

std::string ManText(const CLI::App& app) {
  std::string out = app.help();
  if (const size_t at = out.rfind(app.get_footer()); at != std::string::npos) out.erase(at);
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    std::string help = sub->help(app.get_name());
    const std::string footer = sub->get_footer();
    if (const size_t at = help.rfind(footer); !footer.empty() && at != std::string::npos) help.erase(at);
    // Only -h,--help is left in "Options" (tests/cli_help_test.sh), and that
    // heading would start help2man's OPTIONS section again.
    if (const size_t at = help.find("\nOptions:\n"); at != std::string::npos) {
      help.erase(at, help.find("\n\n", at + 1) - at);
    }
    help.insert(help.find('\n') + 1, "\n");  // the description, then "Usage:" as its own paragraph
    out += "\n*" + app.get_name() + " " + sub->get_name() + "*\n" + help + Footer(sub->get_name(), true);
  }
  return out + "\n*Outputs*\n" + kOutputRuleText + "\n*Exit status*\n" + kExitStatusText;
}

std::string BashCompletion(const CLI::App& app) {
  std::vector<std::string> commands;
  std::ostringstream cases, values;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    const std::string name = sub->get_name();
    commands.push_back(name);
    std::vector<std::string> all;
    for (const CLI::Option* o : sub->get_options()) {
      if (!o->nonpositional() || o->get_group().empty()) continue;  // positionals, hidden options
      const std::vector<std::string> names = Names(*o);
      all.insert(all.end(), names.begin(), names.end());
      if (o->get_type_size_max() == 0) continue;  // a flag: the next word is not its value
      const OptionTopic* t = TopicOf(name, *o);
      const std::string choices = t ? std::string(t->choices) : "";
      std::string pattern;  // 'fit -o'|'fit --output'
      for (const std::string& n : names) pattern += (pattern.empty() ? "'" : "|'") + name + " " + n + "'";
      values << "    " << pattern << ") ";
      if (choices.empty()) {
        values << "return 0 ;;\n";  // a file name or a number: readline's default (-o default)
      } else {
        values << "COMPREPLY=($(compgen -W '" << choices << "' -- \"$cur\"))";
        values << (t->files_too ? "; COMPREPLY+=($(compgen -f -- \"$cur\")); return 0 ;;\n" : "; return 0 ;;\n");
      }
    }
    cases << "    " << name << ") opts='" << Words(all) << "' ;;\n";
  }
  std::vector<std::string> top;
  for (const CLI::Option* o : app.get_options()) {
    if (!o->nonpositional() || o->get_group().empty()) continue;
    const std::vector<std::string> names = Names(*o);
    top.insert(top.end(), names.begin(), names.end());
  }
  std::string pattern;
  for (const std::string& c : commands) pattern += (pattern.empty() ? "" : "|") + c;
  std::ostringstream s;
  s << "# bash completion for zwidth; generated from the command's own option lists by\n"
       "# `zwidth --bash-completion` at build time: do not edit.\n"
       "_zwidth() {\n"
       "  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} cmd= opts= i\n"
       "  COMPREPLY=()\n"
       "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
       "    case ${COMP_WORDS[i]} in\n"
       "      " << pattern << ") cmd=${COMP_WORDS[i]}; break ;;\n"
       "    esac\n"
       "  done\n"
       "  if [[ -z $cmd ]]; then\n"
       "    COMPREPLY=($(compgen -W '" << Words(commands) << " " << Words(top) << "' -- \"$cur\"))\n"
       "    return 0\n"
       "  fi\n"
       "  # the value of an option: its choices, else a file name (readline's default)\n"
       "  if ((COMP_CWORD - 1 > i)); then\n"
       "    case \"$cmd $prev\" in\n"
    << values.str() <<
       "    esac\n"
       "  fi\n"
       "  case $cmd in\n"
    << cases.str() <<
       "  esac\n"
       "  if [[ $cur == -* ]]; then\n"
       "    COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
       "  fi\n"
       "  return 0\n"
       "}\n"
       "complete -o default -F _zwidth zwidth\n";
  return s.str();
}

}  // namespace zwidth::app
