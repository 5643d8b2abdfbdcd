#include "study/DatasetCard.h"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <map>

#include "io/Image.h"
#include "features/Plot.h"
#include "io/AtomicFile.h"
#include "study/GoodnessOfFit.h"
#include "study/Sampler.h"

namespace ltm {

namespace fs = std::filesystem;
using json = io::Json;

namespace {

std::string list_of(const std::vector<long>& v) {
    std::string s;
    for (size_t i = 0; i < v.size() && i < 20; ++i) s += (i ? ", " : "") + std::to_string(v[i]);
    if (v.size() > 20) s += fmt::format(", ... ({} in all)", v.size());
    return s;
}

const char* range_name(Distribution::Range r) {
    switch (r) {
        case Distribution::Range::Any: return "any";
        case Distribution::Range::Positive: return "positive";
        case Distribution::Range::NonNegative: return "non-negative";
    }
    return "any";
}

json law_json(const Distribution& d) {
    static const char* kinds[] = {"constant", "uniform", "log_uniform", "normal"};
    return {{"spec", d.to_string()}, {"law", kinds[static_cast<int>(d.kind)]}, {"a", d.a}, {"b", d.b}, {"range", range_name(d.range)}};
}

json law_json(const Choice& c) { return {{"spec", c.to_string()}, {"law", "choice"}, {"options", c.options}}; }

// A number's law back from its JSON (law_json); throws json's exceptions on a malformed one.
Distribution law_of(const json& j) {
    Distribution d;
    const std::string law = j.at("law").get<std::string>();
    d.kind = law == "uniform"       ? Distribution::Kind::Uniform
             : law == "log_uniform" ? Distribution::Kind::LogUniform
             : law == "normal"      ? Distribution::Kind::Normal
                                    : Distribution::Kind::Constant;
    d.a = j.at("a").get<double>();
    d.b = j.at("b").get<double>();
    const std::string range = j.value("range", std::string("any"));
    d.range = range == "positive"       ? Distribution::Range::Positive
              : range == "non-negative" ? Distribution::Range::NonNegative
                                        : Distribution::Range::Any;
    return d;
}

std::string number(double x) { return fmt::format("{:.4g}", x); }

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One row of the numbers' table: the requested law, the realised values' count, min, median, max
// and mean, and the test against the law.
std::string number_row(const std::string& name, const json& law, const std::vector<double>& values) {
    const Distribution d = law_of(law);
    std::string requested = law.at("spec").get<std::string>();
    if (d.kind == Distribution::Kind::Normal && d.range != Distribution::Range::Any)
        requested += d.range == Distribution::Range::Positive ? " truncated to > 0" : " truncated to >= 0";
    if (values.empty()) return fmt::format("| {} | {} | 0 | | | | | | |\n", name, requested);
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    double mean = 0;
    for (double x : values) mean += x;
    mean /= static_cast<double>(values.size());
    std::string test, p;
    if (d.continuous()) {
        const double D = ks_statistic(values, [&](double x) { return d.cdf(x); });
        test = fmt::format("D = {:.4f}", D);
        p = fmt::format("{:.2g}", ks_pvalue(static_cast<long>(values.size()), D));
    } else {
        const auto differ = std::count_if(values.begin(), values.end(), [&](double x) { return x != d.a; });
        test = "constant";
        p = differ == 0 ? "all equal" : fmt::format("{} differ", differ);
    }
    return fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", name, requested, values.size(), number(*lo),
                       number(median_of(values)), number(*hi), number(mean), test, p);
}

// One row of the words' table: the options' counts, and Pearson's chi-square against equal shares.
std::string word_row(const std::string& name, const json& law, const std::map<std::string, long>& counts) {
    const auto options = law.at("options").get<std::vector<std::string>>();
    long n = 0;
    for (const auto& [w, c] : counts) n += c;
    std::string realised;
    for (const auto& o : options) {
        const auto it = counts.find(o);
        realised += fmt::format("{}{} {}", realised.empty() ? "" : ", ", o, it == counts.end() ? 0 : it->second);
    }
    std::string test = "-", p = "-";
    if (n > 0 && options.size() > 1) {
        const double expected = static_cast<double>(n) / static_cast<double>(options.size());
        double x2 = 0;
        for (const auto& o : options) {
            const auto it = counts.find(o);
            const double c = it == counts.end() ? 0.0 : static_cast<double>(it->second);
            x2 += (c - expected) * (c - expected) / expected;
        }
        test = fmt::format("chi2 = {:.3g} ({} dof)", x2, options.size() - 1);
        p = fmt::format("{:.2g}", chi_square_pvalue(x2, static_cast<int>(options.size()) - 1));
    } else if (n > 0) {
        test = "constant";
        p = counts.size() == 1 && counts.begin()->first == options.front() ? "all equal" : "some differ";
    }
    return fmt::format("| {} | {} | {} | {} | {} | {} |\n", name, law.at("spec").get<std::string>(), n, realised, test, p);
}

// The card's section on sampled parameters: what the spec asked for (identity's "requested")
// against what the samples present drew (their labels' "sampled" values).
std::string parameters_section(const json& requested, const std::vector<json>& labels) {
    std::string numbers, words, counts;
    // The object's varied keys.
    for (const json& p : requested.at("object")) {
        const std::string key = p.at("key").get<std::string>();
        std::vector<double> v;
        for (const json& L : labels)
            if (L.contains("object_sampled") && L["object_sampled"].contains(key)) v.push_back(L["object_sampled"][key].get<double>());
        numbers += number_row("object " + key, p.at("law"), v);
    }
    for (const json& e : requested.at("defects")) {
        const long entry = e.at("entry").get<long>();
        const std::string kind = e.at("kind").get<std::string>();
        const std::string prefix = fmt::format("defects[{}] {} ", entry, kind);
        // The count per sample that is not defect-free.
        std::vector<double> per_sample;
        for (const json& L : labels) {
            if (L.value("defect_free", false)) continue;
            long c = 0;
            for (const json& d : L["defects"]) c += d.value("spec_entry", -1L) == entry;
            per_sample.push_back(static_cast<double>(c));
        }
        if (!per_sample.empty()) {
            const auto [lo, hi] = std::minmax_element(per_sample.begin(), per_sample.end());
            double mean = 0;
            for (double x : per_sample) mean += x;
            mean /= static_cast<double>(per_sample.size());
            counts += fmt::format("| {}count | {} | {} | {} | {} | {} | {} |\n", prefix, e.at("count").get<std::string>(),
                                  per_sample.size(), number(*lo), number(median_of(per_sample)), number(*hi), number(mean));
        }
        for (const json& p : e.at("parameters")) {
            const std::string key = p.at("key").get<std::string>();
            // "semi_axes[i]" is element i of the drawn "semi_axes".
            const auto bracket = key.find('[');
            const std::string base = key.substr(0, bracket);
            const long element = bracket == std::string::npos ? -1 : std::stol(key.substr(bracket + 1));
            std::vector<double> v;
            std::map<std::string, long> w;
            for (const json& L : labels)
                for (const json& d : L["defects"]) {
                    if (d.value("spec_entry", -1L) != entry || !d.contains("sampled") || !d["sampled"].contains(base)) continue;
                    const json& x = element < 0 ? d["sampled"][base] : d["sampled"][base].at(static_cast<size_t>(element));
                    if (x.is_string()) ++w[x.get<std::string>()];
                    else v.push_back(x.get<double>());
                }
            if (p.at("law").at("law") == "choice") words += word_row(prefix + key, p.at("law"), w);
            else numbers += number_row(prefix + key, p.at("law"), v);
        }
    }
    std::string md = "\n## Sampled parameters: requested and realised\n\n";
    md += "Every parameter the spec draws, over the samples present. Numbers: the requested law (a normal is "
          "truncated to its key's range, docs/dataset.md), the realised values, and the one-sample "
          "Kolmogorov-Smirnov statistic D of the values against the requested CDF with its p-value, the "
          "probability of a D at least as large if the values were independent draws of that law (a p far below "
          "0.001 says they are not); a constant is checked for equality.\n\n";
    md += "| parameter | requested | n | min | median | max | mean | test | p |\n|---|---|---|---|---|---|---|---|---|\n";
    md += numbers;
    if (!words.empty()) {
        md += "\nWords chosen from a list: the counts of each option, and Pearson's chi-square against equal shares "
              "with its p-value.\n\n";
        md += "| parameter | requested | n | realised | test | p |\n|---|---|---|---|---|---|\n" + words;
    }
    if (!counts.empty()) {
        md += "\nDefects per sample that is not defect-free. Not tested: a sample's counts are drawn again until it "
              "has 1 to 64 defects in all, so they follow the requested laws conditioned on that.\n\n";
        md += "| parameter | requested | samples | min | median | max | mean |\n|---|---|---|---|---|---|---|\n" + counts;
    }
    return md;
}

}  // namespace

json requested_parameters(const DatasetSpec& spec) {
    json r;
    r["defect_free_fraction"] = spec.defect_free_fraction;
    json splits = json::object();
    for (const auto& s : spec.splits) splits[s.name] = s.fraction;
    r["splits"] = splits;
    json object = json::array();
    for (const auto& [key, law] : varied_object_keys(spec)) object.push_back({{"key", key}, {"law", law_json(*law)}});
    r["object"] = object;
    json defects = json::array();
    for (size_t i = 0; i < spec.defects.size(); ++i) {
        const DefectKindSpec& k = spec.defects[i];
        json parameters = json::array();
        for (const SampledKey& p : sampled_keys(k))
            parameters.push_back({{"key", p.key}, {"law", p.number ? law_json(*p.number) : law_json(*p.word)}});
        defects.push_back({{"entry", i}, {"kind", to_string(k.type)}, {"count", k.count.to_string()}, {"parameters", parameters}});
    }
    r["defects"] = defects;
    return r;
}

void write_dataset_card(const std::string& dir, const json& identity, const std::string& spec_text,
                        const std::vector<json>& labels, long total, const std::vector<long>& missing,
                        const std::vector<long>& corrupt) {
    const fs::path card = fs::path(dir) / "card";
    fs::create_directories(card);
    // Counts per kind and split, sizes per kind.
    std::map<std::string, long> per_kind, visible, samples_with, per_split;
    std::map<std::string, std::vector<double>> sizes, lengths, areas;
    long defect_free = 0;
    for (const json& L : labels) {
        ++per_split[L["split"].get<std::string>()];
        if (L["defects"].empty()) ++defect_free;
        std::map<std::string, bool> seen;
        for (const json& d : L["defects"]) {
            const std::string k = d["kind"].get<std::string>();
            ++per_kind[k];
            if (d["pixel_area"].get<long>() > 0) ++visible[k];
            seen[k] = true;
            sizes[k].push_back(d["parameters"]["size"].get<double>());
            if (d["parameters"].contains("length")) lengths[k].push_back(d["parameters"]["length"].get<double>());
            areas[k].push_back(d["pixel_area"].get<double>());
        }
        for (const auto& [k, _] : seen) ++samples_with[k];
    }
    std::string md = "# ltmsim defect dataset\n\n";
    md += fmt::format("Generated by ltmsim {} from `spec.yaml` (canonical spec SHA-256 `{}`), seed {}.\n\n",
                      identity.value("ltmsim_version", std::string("?")), identity.value("spec_sha256", std::string("?")),
                      identity.value("seed", 0ULL));
    md += fmt::format("- samples: {} of {} present{}{}\n", labels.size(), total,
                      missing.empty() ? "" : fmt::format("; missing: {}", list_of(missing)),
                      corrupt.empty() ? "" : fmt::format("; corrupt (redo with --resume): {}", list_of(corrupt)));
    const json requested = identity.value("requested", json());
    const auto share = [&](const json& f) {
        return f.is_number() ? fmt::format(" (requested share {}: {:.1f} expected)", f.get<double>(),
                                           f.get<double>() * static_cast<double>(labels.size()))
                             : std::string();
    };
    md += fmt::format("- defect-free samples: {}{}\n", defect_free, share(requested.value("defect_free_fraction", json())));
    for (const auto& [s, n] : per_split)
        md += fmt::format("- split `{}`: {} samples{}\n", s, n,
                          share(requested.contains("splits") ? requested["splits"].value(s, json()) : json()));
    md += "\n## Defects per kind\n\n| kind | defects | visible (pixel area > 0) | samples with it |\n|---|---|---|---|\n";
    for (const auto& [k, n] : per_kind) md += fmt::format("| {} | {} | {} | {} |\n", k, n, visible[k], samples_with[k]);
    if (requested.is_object()) {
        try {
            md += parameters_section(requested, labels);
        } catch (const json::exception& e) {
            md += fmt::format("\n## Sampled parameters\n\ndataset.json's requested laws cannot be read ({}).\n", e.what());
        }
    } else {
        md += "\n## Sampled parameters\n\ndataset.json records no requested laws to compare the samples with.\n";
    }
    md += "\n## Sizes\n\n";
    for (const auto& [k, v] : sizes) {
        const std::string what = k == "scratch" ? "width (mm)" : "largest semi-axis (mm)";
        write_png((card / (k + "-size.png")).string(), histogram(v, 20, k + ": " + what, what, true, "defects"));
        md += fmt::format("![{} sizes](card/{}-size.png)\n\n", k, k);
    }
    for (const auto& [k, v] : lengths) {
        write_png((card / (k + "-length.png")).string(), histogram(v, 20, k + ": length (mm)", "length (mm)", false, "defects"));
        md += fmt::format("![{} lengths](card/{}-length.png)\n\n", k, k);
    }
    for (const auto& [k, v] : areas) {
        write_png((card / (k + "-area.png")).string(),
                  histogram(v, 20, k + ": mask area (camera pixels)", "mask area (camera pixels)", false, "defects"));
        md += fmt::format("![{} mask areas](card/{}-area.png)\n\n", k, k);
    }
    md += R"(## Files

- `samples/<i>/scene.yaml`: the sample's scene; `ltmsim render scene.yaml -o OUT` reproduces it bit for bit.
- `samples/<i>/features.exr` and `features.npz`: the feature images (one float32 channel each).
- `samples/<i>/mask.png`: 16-bit instance mask; 0 is background, k is defect k of `scene.yaml` (from 1).
- `samples/<i>/labels.json`: per defect its kind, parameters, the values its spec keys drew (`sampled`), bounding box, pixel area, visibility, RLE mask.
- `index.jsonl`: one line per sample with the checksums of its files; `annotations.json`: COCO.

A camera pixel belongs to defect k when at least `min_fraction` (see `labels.json`) of its sampled
paths meet defect k before any other defect (docs/dataset.md, "Ground truth").

## Loading

```python
import sys; sys.path.insert(0, "path/to/ltmsim/scripts")
from load_dataset import load_sample
features, mask, labels = load_sample("samples/000000")
```

## Spec

```yaml
)" + spec_text + (spec_text.empty() || spec_text.back() == '\n' ? "" : "\n") + "```\n";
    io::write_file((fs::path(dir) / "README.md").string(), md, "dataset card");
}

}  // namespace ltm
