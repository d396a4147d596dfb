//! The FMU's `resources/` folder, found from the `fmuResourceLocation` URI
//! that `fmi2Instantiate` receives. Importers write it in several forms:
//! `file:///abs/path`, `file:/abs/path`, `file://localhost/abs/path`, with
//! percent-encoded characters, and on Windows `file:///C:/dir` or a UNC host.
//! A location that cannot be used is kept as the reason why, and becomes an
//! error only when a model actually needs a file. The instance name comes
//! along: an FMU shared by several instances (libcosim unpacks one copy per
//! GUID) finds each instance's own files by it.

use super::status::{FmiError, FmiResult};
use percent_encoding::percent_decode_str;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Resources {
    place: Place,
    instance: String,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Place {
    Folder(PathBuf),
    /// Why the importer's location is no folder this FMU can read.
    Unusable(String),
}

impl Default for Resources {
    fn default() -> Self {
        Place::Unusable("no resource location was given".into()).into()
    }
}

impl From<Place> for Resources {
    fn from(place: Place) -> Self {
        Resources { place, instance: String::new() }
    }
}

impl Resources {
    /// The location as `fmi2Instantiate` passed it (`None` for NULL).
    pub fn from_location(location: Option<&str>) -> Self {
        parse(location, cfg!(windows))
    }

    /// A folder given as a path (FMI 3.0's `resourcePath`), or why there is none.
    pub fn from_path(path: Option<&str>) -> Self {
        match path {
            Some(p) if !p.is_empty() => Place::Folder(PathBuf::from(p)).into(),
            _ => Place::Unusable("the importer passed no resourcePath".into()).into(),
        }
    }

    /// The same location, for the instance `fmi2Instantiate` named.
    pub fn for_instance(self, instance: &str) -> Self {
        Resources { instance: instance.to_string(), ..self }
    }

    /// The instance name the importer gave ("" when none).
    pub fn instance(&self) -> &str {
        &self.instance
    }

    /// The path of a file in `resources/`; the error says why there is none.
    pub fn file(&self, name: &str) -> FmiResult<PathBuf> {
        match &self.place {
            Place::Folder(folder) => Ok(folder.join(name)),
            Place::Unusable(why) => {
                Err(FmiError::error(format!("cannot read resources/{name} of the FMU: {why}")))
            }
        }
    }

    /// The folder, or why there is none.
    pub fn folder_or_why(&self) -> Result<&Path, &str> {
        match &self.place {
            Place::Folder(folder) => Ok(folder),
            Place::Unusable(why) => Err(why),
        }
    }

    pub fn folder(&self) -> Option<&Path> {
        match &self.place {
            Place::Folder(folder) => Some(folder),
            Place::Unusable(_) => None,
        }
    }
}

/// The URI rules of RFC 8089 that importers use; `windows` selects how a
/// drive letter and a host name become a path.
fn parse(location: Option<&str>, windows: bool) -> Resources {
    place(location, windows).into()
}

fn place(location: Option<&str>, windows: bool) -> Place {
    let Some(uri) = location else {
        return Place::Unusable("the importer passed no fmuResourceLocation (NULL)".into());
    };
    let unusable = |why: &str| Place::Unusable(format!("fmuResourceLocation \"{uri}\" {why}"));
    let Some(rest) = uri.get(..5).filter(|s| s.eq_ignore_ascii_case("file:")).map(|_| &uri[5..]) else {
        return unusable("is not a file: URI");
    };
    // file://host/path or file:/path (no authority).
    let (host, path) = match rest.strip_prefix("//") {
        Some(after) => match after.find('/') {
            Some(i) => (&after[..i], &after[i..]),
            None => (after, ""),
        },
        None => ("", rest),
    };
    if !path.starts_with('/') {
        return unusable("has no absolute path");
    }
    let Ok(decoded) = percent_decode_str(path).decode_utf8() else {
        return unusable("decodes to bytes that are not UTF-8");
    };
    let local = host.is_empty() || host.eq_ignore_ascii_case("localhost");
    let path = decoded.into_owned();
    if windows {
        let drive = path.as_bytes();
        let has_drive = drive.len() >= 3 && drive[1].is_ascii_alphabetic() && drive[2] == b':';
        match (local, has_drive) {
            (true, true) => Place::Folder(PathBuf::from(&path[1..])),
            (true, false) => Place::Folder(PathBuf::from(path)),
            // A share on another machine: \\host\share\...
            (false, _) => Place::Folder(PathBuf::from(format!("\\\\{host}{}", path.replace('/', "\\")))),
        }
    } else if local {
        Place::Folder(PathBuf::from(path))
    } else {
        unusable(&format!("names the host \"{host}\"; only local files can be read"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(location: &str, windows: bool) -> PathBuf {
        match parse(Some(location), windows).folder_or_why() {
            Ok(p) => p.to_path_buf(),
            Err(why) => panic!("{location}: {why}"),
        }
    }

    #[test]
    fn unix_forms() {
        let want = PathBuf::from("/tmp/fmu/resources/");
        assert_eq!(folder("file:///tmp/fmu/resources/", false), want);
        assert_eq!(folder("file:/tmp/fmu/resources/", false), want);
        assert_eq!(folder("file://localhost/tmp/fmu/resources/", false), want);
        assert_eq!(folder("FILE://LocalHost/tmp/fmu/resources/", false), want);
    }

    #[test]
    fn percent_encoded_characters_are_decoded() {
        assert_eq!(folder("file:///tmp/my%20fmu/r%C3%A9sum%C3%A9%25/", false), PathBuf::from("/tmp/my fmu/résumé%/"));
    }

    #[test]
    fn windows_forms() {
        assert_eq!(folder("file:///C:/Users/Ann/AppData/Local/Temp/x/resources", true), PathBuf::from("C:/Users/Ann/AppData/Local/Temp/x/resources"));
        assert_eq!(folder("file:/C:/Users/Ann%20B/resources/", true), PathBuf::from("C:/Users/Ann B/resources/"));
        assert_eq!(folder("file://localhost/D:/fmus/resources", true), PathBuf::from("D:/fmus/resources"));
        assert_eq!(folder("file://server/share/fmus/resources", true), PathBuf::from("\\\\server\\share\\fmus\\resources"));
        // The same URI on Linux (Wine's importers aside) is a path that starts with /C:.
        assert_eq!(folder("file:///C:/Users/x", false), PathBuf::from("/C:/Users/x"));
    }

    #[test]
    fn unusable_locations_say_why_and_fail_only_when_a_file_is_needed() {
        for (location, why) in [
            (None, "NULL"),
            (Some("/tmp/fmu/resources"), "is not a file: URI"),
            (Some("http://example.com/resources"), "is not a file: URI"),
            (Some("file:relative/resources"), "no absolute path"),
            (Some("file://server/share/resources"), "host \"server\""),
            (Some("file:///tmp/%FF%FE/"), "not UTF-8"),
        ] {
            let r = parse(location, false);
            let Err(message) = r.folder_or_why() else { panic!("{location:?} was accepted") };
            assert!(message.contains(why), "{location:?}: {message}");
            let e = r.file("webs.json").unwrap_err();
            assert!(e.message.contains("resources/webs.json") && e.message.contains(why), "{}", e.message);
        }
    }

    #[test]
    fn a_file_is_joined_to_the_folder() {
        let r = parse(Some("file:///opt/fmu/resources/"), false);
        assert_eq!(r.file("webs.json").unwrap(), PathBuf::from("/opt/fmu/resources/webs.json"));
    }

    #[test]
    fn this_platform_reads_its_own_form() {
        #[cfg(windows)]
        assert_eq!(Resources::from_location(Some("file:///C:/fmu/resources")).folder(), Some(Path::new("C:/fmu/resources")));
        #[cfg(not(windows))]
        assert_eq!(Resources::from_location(Some("file:///fmu/resources")).folder(), Some(Path::new("/fmu/resources")));
    }
}
