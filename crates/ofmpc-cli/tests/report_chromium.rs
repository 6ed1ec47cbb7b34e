//! The HTML report in a real browser: headless Chromium loads the page, the inline check script
//! confirms every figure rendered, and a screenshot shows the page is not blank.
//!
//! These tests fail when no Chromium is installed (a skipped browser check would pass while
//! checking nothing): install it with `apt-get install chromium`; `.ci/run` does.

use ofmpc_cli::output;

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{decode_png, edge_case_figure, errors_figure, keep_artifact};
use output::plot::{self, color, COLOR_FIRST, COLOR_USUAL};
use output::report::{Image, Report, Table};

/// Chromium binary: `/usr/bin/chromium`, else the first of the usual names on PATH.
/// Panics, saying how to install it, when there is none.
fn chromium_binary() -> PathBuf {
    find_chromium().expect(
        "Chromium not found (looked for /usr/bin/chromium, chromium, chromium-browser, \
         google-chrome, google-chrome-stable on PATH): the browser tests need it; \
         install it with `apt-get install chromium`",
    )
}

fn find_chromium() -> Option<PathBuf> {
    let fixed = Path::new("/usr/bin/chromium");
    if fixed.is_file() {
        return Some(fixed.to_path_buf());
    }
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in [
            "chromium",
            "chromium-browser",
            "google-chrome",
            "google-chrome-stable",
        ] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Runs headless Chromium with a fresh profile on `page`, plus `extra` arguments; returns
/// stdout. Kills it after two minutes.
fn chromium(bin: &Path, profile: &Path, extra: &[String], page: &Path) -> String {
    let mut cmd = Command::new(bin);
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
    ])
    .arg(format!("--user-data-dir={}", profile.display()))
    .args(extra)
    .arg(format!("file://{}", page.display()))
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    let child = cmd.spawn().expect("start chromium");
    let id = child.id();
    // Watchdog: a hung browser must not hang the test suite.
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    let watchdog = std::thread::spawn(move || {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(120) {
            if rx.recv_timeout(Duration::from_millis(200)).is_ok() {
                return false;
            }
        }
        let _ = Command::new("kill").arg("-9").arg(id.to_string()).status();
        true
    });
    let out = child.wait_with_output().expect("wait for chromium");
    let _ = tx.send(());
    let killed = watchdog.join().unwrap_or(false);
    assert!(!killed, "chromium did not finish within 120 s");
    assert!(
        out.status.success(),
        "chromium failed ({}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Value of attribute `name` in the start tag of the element with id `id` in serialized HTML.
fn attribute(dom: &str, id: &str, name: &str) -> Option<String> {
    let at = dom.find(&format!("id=\"{id}\""))?;
    let tag_start = dom[..at].rfind('<')?;
    let tag_end = at + dom[at..].find('>')?;
    let tag = &dom[tag_start..tag_end];
    let key = format!("{name}=\"");
    let v = &tag[tag.find(&key)? + key.len()..];
    Some(v[..v.find('"')?].to_string())
}

/// A report like the one `ofmpc` writes: text, a table, SVG and PNG figures.
fn sample_report() -> Report {
    let errors = plot::render_both(&errors_figure()).unwrap();
    let edges = plot::render_both(&edge_case_figure()).unwrap();
    let mut r = Report::new("ofmpc report: IRB 140, paper trajectory <test>");
    r.paragraph("Control errors of the First and Second algorithms compared with Usual predictive control & friends.");
    r.table(Table {
        caption: "Table I. RMS control errors".into(),
        header: vec!["controller".into(), "RMS e₂ (mrad)".into()],
        rows: vec![
            vec!["usual".into(), "0.412".into()],
            vec!["first".into(), "0.121".into()],
            vec!["second".into(), "0.057".into()],
        ],
    });
    r.heading("Figures");
    r.figure("Fig. 6 (SVG). Control errors.", Image::Svg(errors.svg));
    r.figure("Fig. 6 (PNG). Control errors.", Image::Png(errors.png));
    r.figure("Edge cases (SVG).", Image::Svg(edges.svg));
    r.figure("Edge cases (PNG).", Image::Png(edges.png));
    r.code("ofmpc reproduce --out results/");
    r
}

#[test]
fn report_renders_all_figures_in_chromium() {
    let report = sample_report();
    let html = report.to_html().unwrap();
    let n = report.figure_count();
    assert_eq!(n, 4);
    // Structure, independent of the browser.
    assert_eq!(
        attribute(&html, "figure-check", "data-total"),
        Some(n.to_string())
    );
    assert_eq!(
        attribute(&html, "figure-check", "data-ok"),
        Some("0".into())
    );
    for i in 1..=n {
        assert!(html.contains(&format!("id=\"figure-{i}\"")));
    }
    assert!(!html.contains("<test>"), "title not escaped");

    let bin = chromium_binary();
    let tmp = tempfile::tempdir().unwrap();
    let page = tmp.path().join("report.html");
    report.write(&page).unwrap();
    keep_artifact("report.html", html.as_bytes());

    let dom = chromium(
        &bin,
        &tmp.path().join("profile1"),
        &["--dump-dom".into()],
        &page,
    );
    assert_eq!(
        attribute(&dom, "figure-check", "data-total"),
        Some(n.to_string()),
        "DOM: {}",
        &dom[..dom.len().min(2000)]
    );
    assert_eq!(
        attribute(&dom, "figure-check", "data-ok"),
        Some(n.to_string())
    );
    assert_eq!(attribute(&dom, "figure-check", "class"), Some("ok".into()));
    for i in 1..=n {
        assert_eq!(
            attribute(&dom, &format!("figure-{i}"), "data-rendered"),
            Some("yes".into())
        );
    }

    let shot = tmp.path().join("shot.png");
    chromium(
        &bin,
        &tmp.path().join("profile2"),
        &[
            format!("--screenshot={}", shot.display()),
            "--window-size=1200,2000".into(),
        ],
        &page,
    );
    let bytes = std::fs::read(&shot).expect("screenshot written");
    keep_artifact("report_screenshot.png", &bytes);
    let img = decode_png(&bytes);
    assert_eq!((img.width, img.height), (1200, 2000));
    let mut non_white = 0usize;
    let mut usual = 0usize;
    let mut first = 0usize;
    let near = |p: [u8; 3], c: plotters::style::RGBColor| {
        (i32::from(p[0]) - i32::from(c.0)).abs() <= 12
            && (i32::from(p[1]) - i32::from(c.1)).abs() <= 12
            && (i32::from(p[2]) - i32::from(c.2)).abs() <= 12
    };
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.pixel(x, y);
            if p.iter().any(|&c| c < 240) {
                non_white += 1;
            }
            usual += usize::from(near(p, color(COLOR_USUAL)));
            first += usize::from(near(p, color(COLOR_FIRST)));
        }
    }
    let total = (img.width * img.height) as usize;
    assert!(
        non_white > total / 100,
        "screenshot nearly blank: {non_white} of {total} pixels"
    );
    assert!(
        usual > 1000 && first > 1000,
        "plot lines not visible: usual {usual}, first {first}"
    );
}

#[test]
fn check_script_detects_a_broken_figure() {
    // Negative control: a PNG with a valid signature but garbage data cannot be decoded, so the
    // page must report fewer rendered figures than it has.
    let bin = chromium_binary();
    let good = plot::render_png(&edge_case_figure()).unwrap();
    let mut r = Report::new("broken");
    // And text that cannot fit: one unbreakable word far wider than the window.
    r.paragraph("x".repeat(600));
    r.figure("good", Image::Png(good));
    r.figure(
        "broken",
        Image::Png(b"\x89PNG\r\n\x1a\nthis is not image data".to_vec()),
    );
    let tmp = tempfile::tempdir().unwrap();
    let page = tmp.path().join("broken.html");
    r.write(&page).unwrap();
    let dom = chromium(
        &bin,
        &tmp.path().join("profile"),
        &["--dump-dom".into()],
        &page,
    );
    assert_eq!(
        attribute(&dom, "figure-check", "data-total"),
        Some("2".into())
    );
    assert_eq!(attribute(&dom, "figure-check", "data-ok"), Some("1".into()));
    assert_eq!(attribute(&dom, "figure-check", "class"), Some("bad".into()));
    assert_eq!(
        attribute(&dom, "figure-2", "data-rendered"),
        Some("no".into())
    );
    // Negative control of the clipped-text check: the long word is past the window's edge.
    let clipped: usize = attribute(&dom, "figure-check", "data-clipped")
        .expect("the clipped-text check ran")
        .parse()
        .unwrap();
    assert!(clipped >= 1, "the clipped word was not seen");
}

/// The text of `s` with the HTML attribute escapes of `report::escape` undone.
fn unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Rows of a run's `timeseries.csv`: header and numbers.
fn timeseries(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The report of a real run in headless Chromium with WebGL (SwiftShader): every figure
/// renders (the interactive charts included), the 3-D replay's canvas draws, moving its slider
/// moves the robot, and the frame shown at sample k has the joint angles of row k of the run's
/// `timeseries.csv` and — by the page's own forward kinematics — its flange position.
#[test]
fn replay_follows_the_timeseries_in_chromium() {
    let bin = chromium_binary();
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("s.toml"),
        "title = \"Replay check\"\ncontrollers = [\"usual\", \"second\", \"ctc\"]\n\
         [payload]\nmasses_kg = [0.25]\n[simulation]\nhold_s = 0.3\nsteady_window_s = 0.1\n",
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_ofmpc"))
        .args(["run", "s.toml", "--out", "o"])
        .current_dir(d)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = d.join("o/report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    keep_artifact("run_report.html", html.as_bytes());
    let mut url = page.clone().into_os_string();
    // Every folded part open, so that the clipped-text check sees all of the page.
    url.push("#replay-check,open-all");
    let dom = chromium(
        &bin,
        &d.join("profile"),
        &[
            "--use-gl=swiftshader".into(),
            "--enable-unsafe-swiftshader".into(),
            "--enable-webgl".into(),
            "--ignore-gpu-blocklist".into(),
            "--virtual-time-budget=10000".into(),
            "--window-size=1200,2000".into(),
            "--dump-dom".into(),
        ],
        Path::new(&url),
    );
    let n: usize = attribute(&dom, "figure-check", "data-total")
        .unwrap()
        .parse()
        .unwrap();
    assert!(n >= 5, "{n} figures");
    assert_eq!(
        attribute(&dom, "figure-check", "data-ok"),
        Some(n.to_string()),
        "not every figure rendered"
    );
    assert!(html.contains("data-kind=\"chart\""), "no interactive chart");
    // With a baseline beside the paper's controllers the page compares them (issue #21): the
    // section, its table and its figure, drawn; and no text anywhere is clipped (HTML text past
    // the window or cut by its box, and the charts' axis labels on their canvases).
    assert!(
        dom.contains(">Controllers compared</h2>"),
        "no comparison section"
    );
    let compare_fig = dom
        .split("<figure ")
        .skip(1)
        .find(|f| f.contains("controllers_compared.png"))
        .expect("the comparison figure");
    assert!(
        compare_fig.contains("data-rendered=\"yes\"") && compare_fig.contains("data-drawn=\"yes\""),
        "the comparison figure did not render"
    );
    assert!(
        compare_fig.contains("data-clipped=\"0\""),
        "the comparison chart's text is clipped"
    );
    assert_eq!(
        attribute(&dom, "figure-check", "data-clipped"),
        Some("0".into()),
        "clipped text: {:?}",
        attribute(&dom, "figure-check", "data-clipped-what")
    );
    assert_eq!(attribute(&dom, "replay", "data-ready"), Some("yes".into()));
    let check = unescape(&attribute(&dom, "replay", "data-check").expect("the replay's check"));
    let frames: serde_json::Value = serde_json::from_str(&check).unwrap();
    let frames = frames.as_array().unwrap();
    assert_eq!(
        frames.len(),
        3 * 4,
        "three runs, four slider positions each"
    );
    for run in ["usual_m0.25", "second_m0.25", "ctc_m0.25"] {
        let (header, rows) = timeseries(&d.join("o").join(run).join("timeseries.csv"));
        let col = |name: &str| header.iter().position(|h| h == name).unwrap();
        let mine: Vec<&serde_json::Value> = frames.iter().filter(|f| f["run"] == run).collect();
        assert_eq!(mine.len(), 4, "{run}");
        let mut hashes = Vec::new();
        for f in &mine {
            let k = f["k"].as_u64().unwrap() as usize;
            let row = &rows[k];
            assert!(
                (f["t"].as_f64().unwrap() - row[col("t")]).abs() < 1e-3,
                "{run} t at {k}"
            );
            for i in 0..6 {
                let q = f["q"][i].as_f64().unwrap();
                let want = row[col(&format!("q{}", i + 1))];
                // 16-bit quantization of the joint's range: ≤ 1e-4 rad.
                assert!(
                    (q - want).abs() < 1e-4,
                    "{run} sample {k}: q{} {q} vs {want}",
                    i + 1
                );
            }
            for (c, name) in ["x", "y", "z"].iter().enumerate() {
                let p = f["flange"][c].as_f64().unwrap();
                let want = row[col(name)];
                assert!(
                    (p - want).abs() < 1e-3,
                    "{run} sample {k}: {name} {p} vs {want}"
                );
            }
            assert!(
                f["ink"].as_u64().unwrap() > 2000,
                "{run}: the canvas is nearly empty"
            );
            hashes.push(f["hash"].as_u64().unwrap());
        }
        assert_eq!(
            mine[3]["k"].as_u64().unwrap() as usize,
            rows.len() - 1,
            "last frame is the last sample"
        );
        hashes.dedup();
        assert!(
            hashes.len() >= 3,
            "{run}: the slider did not move the robot: {hashes:?}"
        );
    }
    // The controller's predicted horizon (issue #25): at the frame of a recorded horizon the
    // page draws a polyline that starts at the current sample's flange position, and its
    // points (the page's forward kinematics of the predicted joints) lie on what the flange did
    // next (the timeseries' x, y, z of the following samples). ctc has no horizon.
    let check = unescape(
        &attribute(&dom, "replay", "data-horizon-check").expect("the replay's horizon check"),
    );
    let horizons: serde_json::Value = serde_json::from_str(&check).unwrap();
    let horizons = horizons.as_array().unwrap();
    let names: Vec<&str> = horizons
        .iter()
        .map(|h| h["run"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["usual_m0.25", "second_m0.25"],
        "runs with a horizon"
    );
    for h in horizons {
        let run = h["run"].as_str().unwrap();
        let (header, rows) = timeseries(&d.join("o").join(run).join("timeseries.csv"));
        let col = |name: &str| header.iter().position(|c| c == name).unwrap();
        let k = h["k"].as_u64().unwrap() as usize;
        let hz = &h["horizon"];
        assert_eq!(
            hz["k"].as_u64(),
            Some(k as u64),
            "{run}: horizon of another sample"
        );
        let pts: Vec<f64> = hz["pts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(
            pts.len(),
            3 * 11,
            "{run}: the flange and N = 10 predicted points"
        );
        for c in 0..3 {
            let flange = h["flange"][c].as_f64().unwrap();
            assert!(
                (pts[c] - flange).abs() < 1e-4,
                "{run}: the horizon does not start at the current sample"
            );
        }
        for j in 1..=10 {
            let Some(row) = rows.get(k + j) else { break };
            let d2: f64 = ["x", "y", "z"]
                .iter()
                .enumerate()
                .map(|(c, name)| (pts[3 * j + c] - row[col(name)]).powi(2))
                .sum();
            assert!(
                d2.sqrt() < 1e-3,
                "{run} sample {k}: predicted point {j} is {:.3e} m from the flange's",
                d2.sqrt()
            );
        }
    }
}

/// The replay's data embedded in a report page (`<script id="replay-data">`).
fn replay_data(html: &str) -> serde_json::Value {
    let start =
        html.find("id=\"replay-data\">").expect("the replay's data") + "id=\"replay-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

/// Issue #25 item 4: a robot whose URDF has visual meshes (the test arm of
/// `tests/data/mesh_arm`: binary and ASCII STL, Collada through `package://`, OBJ, and
/// primitives) is drawn from them. The page embeds one mesh per body in the box worked out
/// from the files; in headless Chromium the meshes' colours cover the screen around each
/// body's projected centre at every checked frame, there is no script or WebGL error, and the
/// frames still have the joint angles and flange position of the timeseries.
#[test]
fn mesh_robot_renders_in_chromium() {
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_arm/urdf/mesh_arm.urdf");
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("s.toml"),
        format!(
            "title = \"Mesh check\"\ncontrollers = [\"second\"]\n[robot]\nmodel = {:?}\ndrives = {:?}\n\
             [payload]\nmasses_kg = [0.25]\n[simulation]\nhold_s = 0.2\nsteady_window_s = 0.1\n",
            urdf.display().to_string(),
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../ofmpc/robots/irb140/drives.toml")
                .display()
                .to_string()
        ),
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_ofmpc"))
        .args(["run", "s.toml", "--out", "o"])
        .current_dir(d)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        !stderr.contains("3-D replay"),
        "a mesh was not drawn: {stderr}"
    );
    let page = d.join("o/report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    keep_artifact("mesh_report.html", html.as_bytes());
    assert!(html.contains("drawn from its URDF's visual meshes"));
    let data = replay_data(&html);
    let meshes = data["robot"]["meshes"].as_array().expect("meshes embedded");
    let bodies: Vec<u64> = meshes.iter().map(|m| m["body"].as_u64().unwrap()).collect();
    assert_eq!(bodies, [0, 1, 2, 3, 4, 5, 6]);
    assert_eq!(data["robot"]["capsules"], serde_json::json!(vec![false; 7]));
    // The Collada link: centimetres, node matrix, package:// (see mesh::visuals' tests).
    let link2 = &meshes[2];
    for (c, (lo, hi)) in [(-0.06, 0.06), (-0.09, -0.03), (0.0, 0.36)]
        .iter()
        .enumerate()
    {
        assert!(
            (link2["lo"][c].as_f64().unwrap() - lo).abs() < 1e-9,
            "{link2}"
        );
        assert!(
            (link2["hi"][c].as_f64().unwrap() - hi).abs() < 1e-9,
            "{link2}"
        );
    }
    assert!(!html.contains("Not drawn:"));

    let bin = chromium_binary();
    let mut url = page.clone().into_os_string();
    url.push("#replay-check");
    let dom = chromium(
        &bin,
        &d.join("profile"),
        &[
            "--use-gl=swiftshader".into(),
            "--enable-unsafe-swiftshader".into(),
            "--enable-webgl".into(),
            "--ignore-gpu-blocklist".into(),
            "--virtual-time-budget=10000".into(),
            "--window-size=1200,2000".into(),
            "--dump-dom".into(),
        ],
        Path::new(&url),
    );
    assert_eq!(attribute(&dom, "replay", "data-ready"), Some("yes".into()));
    assert_eq!(
        attribute(&dom, "replay", "data-errors").map(|e| unescape(&e)),
        None,
        "script or WebGL errors"
    );
    let check = unescape(&attribute(&dom, "replay", "data-check").expect("the replay's check"));
    let frames: serde_json::Value = serde_json::from_str(&check).unwrap();
    let frames = frames.as_array().unwrap();
    assert_eq!(frames.len(), 4);
    let (header, rows) = timeseries(&d.join("o/second_m0.25/timeseries.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for f in frames {
        let k = f["k"].as_u64().unwrap() as usize;
        for i in 0..6 {
            let q = f["q"][i].as_f64().unwrap();
            let want = rows[k][col(&format!("q{}", i + 1))];
            assert!(
                (q - want).abs() < 1e-4,
                "sample {k}: q{} {q} vs {want}",
                i + 1
            );
        }
        for (c, name) in ["x", "y", "z"].iter().enumerate() {
            let p = f["flange"][c].as_f64().unwrap();
            assert!((p - rows[k][col(name)]).abs() < 1e-3, "sample {k}: {name}");
        }
        let probes = f["meshes"].as_array().unwrap();
        assert_eq!(probes.len(), 7);
        for p in probes {
            // Each mesh drawn alone covers pixels of its colour inside the screen box of its
            // projected bounding box and none outside (the flange's box, the smallest, is
            // about 20 × 6 px).
            let (inside, outside) = (
                p["inside"].as_u64().unwrap(),
                p["outside"].as_u64().unwrap(),
            );
            assert!(
                inside >= 30 && outside <= 5,
                "sample {k}: body {} not drawn at its place: {p}",
                p["body"]
            );
        }
    }
}
