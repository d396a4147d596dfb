//! line-description LINE_JSON OUT_DIR: the model descriptions of the line in
//! LINE_JSON, as the Line FMU's binary will read it (OUT_DIR/modelDescription.xml,
//! FMI 2.0; OUT_DIR/fmi3/modelDescription.xml and terminalsAndIcons.xml,
//! FMI 3.0), checked as every model description of this project is.

use line::{xml, Line};
use std::path::PathBuf;
use std::process::ExitCode;

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [spec_path, out] = args.as_slice() else {
        return Err("usage: line-description LINE_JSON OUT_DIR".into());
    };
    let text = std::fs::read_to_string(spec_path).map_err(|e| format!("cannot read {spec_path}: {e}"))?;
    let line = Line::from_spec(&text).map_err(|e| e.into_message())?;
    let fmi2 = xml::model_description(&line, line.spec())?;
    let problems = fmi_build::check_description(&fmi2);
    if !problems.is_empty() {
        return Err(format!("the description written for {spec_path} has problems:\n  - {}", problems.join("\n  - ")));
    }
    let (fmi3, terminals) = fmi_build::fmi3_files(&fmi2).map_err(|p| format!("FMI 3.0 form: {}", p.join("; ")))?;
    let out = PathBuf::from(out);
    let write = |path: PathBuf, text: &str| -> Result<(), String> {
        std::fs::create_dir_all(path.parent().expect("a file in a folder")).map_err(|e| format!("{}: {e}", path.display()))?;
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    write(out.join("modelDescription.xml"), &fmi2)?;
    write(out.join("fmi3").join("modelDescription.xml"), &fmi3)?;
    write(out.join("fmi3").join("terminalsAndIcons.xml"), &terminals)?;
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("line-description: {e}");
            ExitCode::FAILURE
        }
    }
}
