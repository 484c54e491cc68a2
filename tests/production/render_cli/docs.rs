//! What the documentation promises: the installed command, the scene READMEs' numbers and commands, the README's
//! links, the results page.

use super::*;

#[test]
fn an_installed_firemedium_finds_its_plugin_from_any_directory() {
    // tools/install.sh's layout — PREFIX/bin/firemedium, PREFIX/lib/firemedium/<plugin> — copied from the build,
    // run from an unrelated directory with no plugin variables: it finds its plugin relative to itself, renders
    // the default scene, and writes where it is told.
    let dir = tmp("install");
    let exe = crate::common::exe("firemedium");
    let lib = firemedium_loader::library_file_name();
    // (Beside the binary after `cargo build`, in `deps` after `cargo test` alone.)
    let plugin = [
        exe.parent().unwrap().join(&lib),
        exe.parent().unwrap().join("deps").join(&lib),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .expect("the plugin is built");
    std::fs::create_dir_all(dir.join("prefix/bin")).unwrap();
    std::fs::create_dir_all(dir.join("prefix/lib/firemedium")).unwrap();
    std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
    let installed = dir.join("prefix/bin").join(exe.file_name().unwrap());
    std::fs::copy(&exe, &installed).unwrap();
    std::fs::copy(&plugin, dir.join("prefix/lib/firemedium").join(&lib)).unwrap();
    let scene = crate::common::root().join("scenes/campfire/scene.pbrt");
    let o = Command::new(&installed)
        .current_dir(dir.join("elsewhere"))
        .env_remove("FIREMEDIUM_PLUGIN")
        .env_remove("FIREMEDIUM_PLUGIN_PATH")
        .args([
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "32x18",
            "--spp",
            "1",
        ])
        .args(["-o", "here.exr", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("elsewhere/here.exr").is_file() && dir.join("elsewhere/here.png").is_file());
    // Every gallery scene, from there, by its absolute path.
    let gallery = crate::common::root().join("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&gallery)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .flat_map(|d| {
            std::fs::read_dir(d)
                .unwrap()
                .filter_map(|e| e.ok().map(|e| e.path()))
        })
        .filter(|p| p.extension().is_some_and(|x| x == "pbrt"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 15, "{scenes:?}");
    for s in &scenes {
        let o = Command::new(&installed)
            .current_dir(dir.join("elsewhere"))
            .env_remove("FIREMEDIUM_PLUGIN")
            .env_remove("FIREMEDIUM_PLUGIN_PATH")
            .arg("render")
            .arg(s.canonicalize().unwrap())
            .args([
                "--resolution",
                "8x6",
                "--spp",
                "1",
                "-o",
                "g.exr",
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{}: {}",
            s.display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // Without the plugin beside it, the message says where it looked.
    std::fs::remove_file(dir.join("prefix/lib/firemedium").join(&lib)).unwrap();
    let o = Command::new(&installed)
        .current_dir(dir.join("elsewhere"))
        .env_remove("FIREMEDIUM_PLUGIN")
        .env_remove("FIREMEDIUM_PLUGIN_PATH")
        .args([
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "32x18",
            "--spp",
            "1",
        ])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("no firemedium plugin found")
            && e.contains("lib/firemedium"),
        "{e}"
    );
}

#[test]
fn scene_readmes_quote_what_render_stats_prints() {
    // A scene README's numbers from `render --stats` are quoted verbatim in backticks — a span holding
    // "plugin built", "fire light:" or ending in a number of lm or W — with "…" for what is left out; each piece
    // must appear in the stats of one of the folder's scenes (rendered at 8×6, 1 spp: the plugin's build and the
    // fire light do not depend on the film). A number that drifts fails here, not in a reader's hands.
    let root = crate::common::root().join("scenes");
    let dir = tmp("readme-stats");
    let mut checked = 0;
    let mut folders: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("README.md").is_file())
        .collect();
    folders.sort();
    for folder in folders {
        let readme = std::fs::read_to_string(folder.join("README.md")).unwrap();
        let quotes: Vec<&str> = readme
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|q| {
                q.contains("plugin built")
                    || q.contains("fire light:")
                    || ((q.ends_with(" lm") || q.ends_with(" W"))
                        && q.chars().next().is_some_and(|c| c.is_ascii_digit()))
            })
            .collect();
        if quotes.is_empty() {
            continue;
        }
        let mut stats = String::new();
        let mut scenes: Vec<PathBuf> = std::fs::read_dir(&folder)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "pbrt"))
            .collect();
        scenes.sort();
        for scene in scenes {
            let out = dir.join("s.exr");
            let o = Command::new(crate::common::exe("firemedium"))
                .arg("render")
                .arg(&scene)
                .args([
                    "--resolution",
                    "8x6",
                    "--spp",
                    "1",
                    "--stats",
                    "--quiet",
                    "-o",
                ])
                .arg(&out)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            stats += &String::from_utf8_lossy(&o.stdout);
            stats += &String::from_utf8_lossy(&o.stderr);
        }
        for q in quotes {
            for piece in q.split('…').map(str::trim).filter(|p| !p.is_empty()) {
                assert!(
                    stats.contains(piece),
                    "{}: `{q}` — '{piece}' is not in what render --stats prints:\n{stats}",
                    folder.join("README.md").display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 15, "{checked} quotes checked");
}

#[test]
fn the_readmes_quick_commands_run_as_written() {
    // Every `firemedium …` (or `target/release/firemedium …`) line of the README's sh blocks whose
    // command is quick — physics, info, tonemap, the quick gens and benches, the adaptation scene's render —
    // runs as written (this build's binary standing for `firemedium`) in a copy of the repository's scenes and
    // test data, in the README's order, and succeeds.
    let root = crate::common::root();
    let dir = tmp("readme");
    copy_dir(&root.join("scenes"), &dir.join("scenes"));
    copy_dir(&root.join("tests/data"), &dir.join("tests/data"));
    // (The README's first steps, then the rendering guide its commands moved to.)
    let readme = ["README.md", "docs/guide/rendering.md"]
        .iter()
        .map(|f| std::fs::read_to_string(root.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))
        .collect::<Vec<_>>()
        .join("\n");
    let mut in_sh = false;
    let mut commands: Vec<Vec<String>> = Vec::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = line == "```sh" && !in_sh;
            continue;
        }
        if !in_sh {
            continue;
        }
        // (A comment starts at " # "; `pool.####.vdb` is not one.)
        let cmd = line.split(" # ").next().unwrap_or("").trim();
        let rest = cmd
            .strip_prefix("target/release/firemedium ")
            .or_else(|| cmd.strip_prefix("firemedium "));
        let Some(rest) = rest else { continue };
        let args: Vec<String> = rest.split_whitespace().map(String::from).collect();
        let quick = match args.first().map(String::as_str) {
            Some("physics" | "info" | "tonemap") => true,
            Some("bench") => matches!(
                args.get(1).map(String::as_str),
                Some("stability" | "components")
            ),
            Some("gen") => args.iter().any(|a| a == "torch" || a == "--embers"),
            Some("render") => args
                .get(1)
                .is_some_and(|s| s == "scenes/adaptation/scene.pbrt"),
            _ => false,
        };
        if quick {
            commands.push(args);
        }
    }
    let names: Vec<String> = commands
        .iter()
        .map(|a| a[..2.min(a.len())].join(" "))
        .collect();
    for want in [
        "physics --temperature",
        "info tests/data/valid/vdb/mantaflow_fire_f060.vdb",
        "tonemap scenes/adaptation/adaptation.exr",
        "bench stability",
        "bench components",
        "gen torch",
        "gen campfire",
        "render scenes/adaptation/scene.pbrt",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "the README and the rendering guide no longer show `firemedium {want} …`: {names:?}"
        );
    }
    for args in &commands {
        let o = firemedium_in(&dir, &args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            o.status.success(),
            "firemedium {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    for f in [
        "night.png",
        "day.png",
        "torch.vdb",
        "campfire.vdb",
        "campfire.embers.ply",
    ] {
        assert!(dir.join(f).is_file(), "{f} was not written");
    }
}

#[test]
fn the_readme_is_short_and_its_links_lead_somewhere() {
    // The README is the newcomer's page: what it is, the two commands, a first scene, where to go next — at most
    // about 8 KB; every relative link in it and in the guides names a file that exists.
    let root = crate::common::root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.len() <= 8 * 1024,
        "README.md is {} bytes",
        readme.len()
    );
    for want in [
        "cargo build --release && target/release/firemedium render scenes/campfire/scene.pbrt",
        "cargo test --workspace --release",
        "firemedium scene fire.vdb",
    ] {
        assert!(readme.contains(want), "the README lost `{want}`");
    }
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs/guide")).unwrap() {
        files.push(e.unwrap().path());
    }
    let mut broken = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, _) in text.match_indices("](") {
            let link: String = text[i + 2..]
                .chars()
                .take_while(|&c| c != ')' && c != '#' && c != ' ')
                .collect();
            if link.is_empty() || link.starts_with("http") {
                continue;
            }
            if !f.parent().unwrap().join(&link).exists() {
                broken.push(format!("{}: {link}", f.display()));
            }
        }
    }
    assert!(broken.is_empty(), "links to nothing: {broken:?}");
}

#[test]
fn the_results_page_gives_each_figure_a_command_and_a_log_entry_that_exists() {
    // docs/results/README.md: one row per topic — the current figure, the command that reproduces it, and a link
    // to the log entry that measured it, whose heading must still exist (GitHub's anchor: lower case, spaces to
    // hyphens, punctuation dropped). No internal issue numbers in it.
    let dir = crate::common::root().join("docs/results");
    let page = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let log = std::fs::read_to_string(dir.join("log.md")).unwrap();
    let anchors: Vec<String> = log
        .lines()
        .filter_map(|l| l.strip_prefix("## "))
        .map(|h| {
            h.trim()
                .to_lowercase()
                .chars()
                .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
                .map(|c| if c == ' ' { '-' } else { c })
                .collect()
        })
        .collect();
    let rows: Vec<&str> = page
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| topic"))
        .collect();
    assert!(rows.len() >= 10, "{} rows", rows.len());
    for row in rows {
        let cells: Vec<&str> = row.split(" | ").collect();
        assert!(cells.len() >= 4, "{row}");
        assert!(cells[2].contains('`'), "no command: {row}");
        let anchor = row
            .split("(log.md#")
            .nth(1)
            .and_then(|r| r.split(')').next())
            .unwrap_or_else(|| panic!("no log entry: {row}"));
        assert!(
            anchors.iter().any(|a| a == anchor),
            "no log heading for #{anchor}"
        );
    }
    assert!(
        !page.to_lowercase().contains("issue "),
        "an issue number in the results page"
    );
}

/// Copies the folder `from` into `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().filter_map(|e| e.ok()) {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_dir(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}
