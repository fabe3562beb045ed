//! `atmo bench`: what its JSON lines carry.

mod common;

use common::atmo;

/// Each line of `atmo bench --json` reports the peak memory of its case (clouds, the
/// quickest area: 3 s).
#[test]
fn bench_lines_report_their_peak_memory() {
    let o = atmo(&["bench", "clouds", "--quick", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines.len() >= 2, "{stdout}");
    // Every order against the path tracer: its error and the two times.
    let multiple = lines
        .iter()
        .find(|l| l.contains("\"bench\":\"clouds.multiple\""))
        .unwrap_or_else(|| panic!("no clouds.multiple in {stdout}"));
    for field in [
        "\"scattering\":\"multiple\"",
        "\"vs_path_traced\":",
        "\"blocks_within_15\":",
        "\"block_medians_within_15\":",
        "\"ratio\":",
    ] {
        assert!(multiple.contains(field), "{field} in {multiple}");
    }
    for line in lines {
        let field = line
            .split("\"peak_rss_mb\":")
            .nth(1)
            .unwrap_or_else(|| panic!("no peak_rss_mb in {line}"));
        let mb: f64 = field
            .split([',', '}'])
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{line}"));
        // A case holds at least its buffer, and far less than the budget.
        assert!(mb > 1.0 && mb < 2048.0, "{line}");
    }
}

/// docs/benchmarks.md is what `atmo bench page` makes of docs/bench/*.json: the page
/// never says what the data does not.
#[test]
fn the_benchmarks_page_is_made_from_the_checked_in_data() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let from = format!("{root}/docs/bench");
    let o = atmo(&["bench", "page", "--from", &from]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = std::fs::read_to_string(format!("{root}/docs/benchmarks.md")).unwrap();
    assert!(
        String::from_utf8_lossy(&o.stdout) == page,
        "docs/benchmarks.md differs from docs/bench/*.json: run \
         `cargo run --release -p atmo-cli -- bench page -o docs/benchmarks.md`"
    );
    // Every family's file has a section, and every case a row.
    for entry in std::fs::read_dir(&from).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let family = path.file_stem().unwrap().to_string_lossy().into_owned();
            assert!(page.contains(&format!("## {family}\n")), "{family}");
            let text = std::fs::read_to_string(&path).unwrap();
            for line in text.lines().filter(|l| !l.trim().is_empty()) {
                let case: serde_json::Value = serde_json::from_str(line).unwrap();
                let name = case["bench"].as_str().unwrap();
                assert!(page.contains(&format!("| `{name}`")), "{name}");
            }
        }
    }
}

/// `atmo bench farm --quick`: each split against one process, its outputs the same
/// bytes, and the per-frame cost; every time measured from the pieces' processes.
#[test]
fn the_farm_bench_compares_pieces_with_one_process() {
    let scenes = common::scene(".");
    let o = atmo(&["bench", "farm", "--quick", "--json", "--scenes", &scenes]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let names: Vec<&str> = lines.iter().map(|l| l["bench"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        ["farm.show", "farm.show", "farm.frame", "farm.table"]
    );
    for line in &lines {
        // A child's CPU time is measured (wait4), not the bench's own (near zero).
        assert!(line["cpu_ms"].as_f64().unwrap() > 10.0, "{line}");
        assert!(line["median_ms"].as_f64().unwrap() > 0.0, "{line}");
        if line["bench"] != "farm.frame" {
            assert_eq!(line["identical"], true, "{line}");
            let ratio = line["ratio"].as_f64().unwrap();
            assert!(ratio > 0.0 && ratio < 10.0, "{line}");
        }
    }
    assert_eq!(lines[0]["params"]["chunks"], 4);
    assert_eq!(lines[3]["params"]["parts"], 8);
}

/// `atmo bench memory --quick`: for each input a knob sizes, the largest value accepted
/// under 64 MiB and the next refused, each measured from its own process; none reaches
/// past the budget by more than a quarter beyond its command's footprint (the bench
/// fails if one does), and a refused run stops before it holds the budget.
#[test]
fn the_memory_bench_holds_each_input_to_the_budget() {
    let scenes = common::scene(".");
    let o = atmo(&["bench", "memory", "--quick", "--json", "--scenes", &scenes]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let measured: Vec<&serde_json::Value> = lines
        .iter()
        .filter(|l| l.get("skipped").is_none())
        .collect();
    // Every CPU input (the GPU's is skipped where there is no adapter).
    assert!(measured.len() >= 5, "{lines:?}");
    for line in measured {
        let p = &line["params"];
        let (accepted, refused) = (
            p["largest_accepted"].as_u64().unwrap(),
            p["refused_at"].as_u64().unwrap(),
        );
        assert!(
            accepted < refused && accepted > p["smallest"].as_u64().unwrap(),
            "{line}"
        );
        assert!(line["ratio_to_budget"].as_f64().unwrap() <= 1.25, "{line}");
        assert!(
            line["refused_peak_rss_mb"].as_f64().unwrap()
                < line["footprint_mb"].as_f64().unwrap() + 64.0,
            "{line}"
        );
    }
}
