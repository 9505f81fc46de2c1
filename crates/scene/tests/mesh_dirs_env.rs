//! `LoadOptions::from_env`: the mesh directories from `SSS_MESH_DIR`. In a test binary of its
//! own, because it sets the process's environment: its one test is the only thread reading it.

use sss_scene::LoadOptions;
use std::path::PathBuf;

fn set(value: Option<&std::ffi::OsStr>) {
    // SAFETY: this binary has one test, and it runs no other thread while it sets the
    // environment, so nothing reads the environment concurrently.
    unsafe {
        match value {
            Some(v) => std::env::set_var("SSS_MESH_DIR", v),
            None => std::env::remove_var("SSS_MESH_DIR"),
        }
    }
}

#[test]
fn mesh_dirs_come_from_sss_mesh_dir_split_like_path() {
    let dirs = [
        PathBuf::from("/meshes/a"),
        PathBuf::from(""),
        PathBuf::from("rel/b"),
    ];
    let joined = std::env::join_paths(&dirs).expect("no separator in the names");
    set(Some(&joined));
    // In order, the empty entry dropped.
    assert_eq!(
        LoadOptions::from_env().mesh_dirs,
        [PathBuf::from("/meshes/a"), PathBuf::from("rel/b")]
    );
    set(Some("".as_ref()));
    assert!(LoadOptions::from_env().mesh_dirs.is_empty());
    set(None);
    assert!(LoadOptions::from_env().mesh_dirs.is_empty());
}
