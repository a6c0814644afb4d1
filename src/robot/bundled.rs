//! The nominal robots of `scans/robots/`, compiled into the library so that
//! `--robot NAME` works from an installed binary as well as from the
//! repository: the wheelchair (the default) and the robots behind the shared
//! real data.

/// `(name, TOML text)` of every robot file in `scans/robots/`; the name is the
/// file's stem.
pub const BUNDLED_ROBOTS: [(&str, &str); 4] = [
    (
        "wheelchair",
        include_str!("../../scans/robots/wheelchair.toml"),
    ),
    (
        "lego-robot",
        include_str!("../../scans/robots/lego-robot.toml"),
    ),
    (
        "mines-rover",
        include_str!("../../scans/robots/mines-rover.toml"),
    ),
    ("khepera", include_str!("../../scans/robots/khepera.toml")),
];

/// The TOML text of the bundled robot `name` (a file stem of `scans/robots/`,
/// with or without `.toml`), if there is one.
pub fn bundled_robot(name: &str) -> Option<&'static str> {
    let stem = name.strip_suffix(".toml").unwrap_or(name);
    BUNDLED_ROBOTS
        .iter()
        .find(|(n, _)| *n == stem)
        .map(|(_, text)| *text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotConfig;

    #[test]
    fn every_robot_file_is_bundled_and_loads() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/robots");
        let mut stems = Vec::new();
        for e in std::fs::read_dir(dir).unwrap() {
            let path = e.unwrap().path();
            let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
            let on_disk = std::fs::read_to_string(&path).unwrap();
            assert_eq!(bundled_robot(&stem), Some(on_disk.as_str()), "{stem}");
            stems.push(stem);
        }
        assert_eq!(stems.len(), BUNDLED_ROBOTS.len());
        for (name, text) in BUNDLED_ROBOTS {
            let c = RobotConfig::from_toml(text).unwrap();
            assert_eq!(c.name, name, "the file's name key is its stem");
        }
        assert!(bundled_robot("lego-robot.toml").is_some());
        assert!(bundled_robot("scans/robots/lego-robot.toml").is_none());
    }
}
