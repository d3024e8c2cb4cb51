//! `scripts/ensure-vulkan.sh` against ICD folders made for each case: a driver in either
//! folder (or named by the loader's variables) is found without running apt-get, and a
//! user without root or sudo is told what to install.

#![cfg(unix)]

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Two ICD folders, and a PATH holding only a fake `id` (reporting `uid`) and a fake
/// `apt-get` that logs its calls and, on `install`, drops a manifest into the second
/// folder as the real package would.
struct Sandbox {
    dir: PathBuf,
}

impl Sandbox {
    fn new(name: &str, uid: u32) -> Sandbox {
        let dir = std::env::temp_dir().join(format!(
            "meshlight-ensure-vulkan-{name}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        for sub in ["icd_a", "icd_b", "bin"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let bin = dir.join("bin");
        script(&bin.join("id"), &format!("echo {uid}"));
        script(
            &bin.join("apt-get"),
            &format!(
                "echo \"$@\" >> {log}\ncase \"$*\" in *install*) echo '{{}}' > {icd}/lvp.json;; esac",
                log = dir.join("apt.log").display(),
                icd = dir.join("icd_b").display()
            ),
        );
        std::os::unix::fs::symlink(which("env"), bin.join("env")).unwrap();
        Sandbox { dir }
    }

    fn run(&self, env: &[(&str, &str)]) -> Output {
        let dirs = format!(
            "{}:{}",
            self.dir.join("icd_a").display(),
            self.dir.join("icd_b").display()
        );
        let mut cmd = Command::new(which("bash"));
        cmd.arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scripts/ensure-vulkan.sh"
        ))
        .env_clear()
        .env("PATH", self.dir.join("bin"))
        .env("MESHLIGHT_VULKAN_ICD_DIRS", dirs);
        for (k, v) in env {
            cmd.env(k, v);
        }
        cmd.output().expect("bash runs")
    }

    fn apt_calls(&self) -> String {
        std::fs::read_to_string(self.dir.join("apt.log")).unwrap_or_default()
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn script(path: &Path, body: &str) {
    std::fs::write(path, format!("#!/bin/sh\n{body}\n")).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A program on this process's PATH (the script's own PATH holds only the fakes).
fn which(program: &str) -> PathBuf {
    std::env::split_paths(&std::env::var_os("PATH").unwrap())
        .map(|d| d.join(program))
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("{program} is not on PATH"))
}

fn text(out: &Output) -> String {
    format!(
        "status {:?}\n{}{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn a_manifest_in_either_folder_is_a_driver_even_when_the_other_is_empty() {
    for (folder, name) in [("icd_a", "first"), ("icd_b", "second")] {
        let sandbox = Sandbox::new(name, 1000);
        std::fs::write(sandbox.dir.join(folder).join("lvp_icd.json"), "{}").unwrap();
        let out = sandbox.run(&[]);
        assert_eq!(out.status.code(), Some(0), "{folder}: {}", text(&out));
        assert_eq!(sandbox.apt_calls(), "", "{folder}: apt-get ran");
    }
}

#[test]
fn a_driver_named_by_the_loaders_variables_is_found() {
    for var in ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"] {
        let sandbox = Sandbox::new(var, 1000);
        let manifest = sandbox.dir.join("elsewhere.json");
        std::fs::write(&manifest, "{}").unwrap();
        let value = format!("/no/such/driver.json:{}", manifest.display());
        let out = sandbox.run(&[(var, &value)]);
        assert_eq!(out.status.code(), Some(0), "{var}: {}", text(&out));
        assert_eq!(sandbox.apt_calls(), "", "{var}: apt-get ran");
        // A variable naming only files that do not exist finds nothing.
        let out = sandbox.run(&[(var, "/no/such/driver.json")]);
        assert_eq!(out.status.code(), Some(2), "{var}: {}", text(&out));
    }
}

#[test]
fn without_a_driver_root_or_sudo_it_says_what_to_install_and_fails() {
    let sandbox = Sandbox::new("no-root", 1000);
    let out = sandbox.run(&[]);
    let said = text(&out);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(
        said.contains("no Vulkan driver found")
            && said.contains("root or sudo")
            && said.contains("mesa-vulkan-drivers"),
        "{said}"
    );
    assert_eq!(sandbox.apt_calls(), "", "apt-get ran without root");
}

#[test]
fn without_a_driver_root_installs_lavapipe_once() {
    let sandbox = Sandbox::new("root", 0);
    let out = sandbox.run(&[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let calls = sandbox.apt_calls();
    assert!(
        calls.contains("install -y -qq mesa-vulkan-drivers"),
        "{calls}"
    );
    // Installed now: the next run finds it and leaves apt-get alone.
    let out = sandbox.run(&[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert_eq!(sandbox.apt_calls(), calls);
}
