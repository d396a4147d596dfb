//! `fmi3-description <FMI 2.0 modelDescription.xml> <folder>`: writes the FMU's
//! FMI 3.0 modelDescription.xml and terminalsAndIcons/terminalsAndIcons.xml
//! into <folder> (fmu/package.py runs it for the FMI 3.0 FMUs).

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, source, folder] = &args[..] else {
        eprintln!("usage: fmi3-description <FMI 2.0 modelDescription.xml> <output folder>");
        std::process::exit(2);
    };
    let xml = std::fs::read_to_string(source).unwrap_or_else(|e| {
        eprintln!("fmi3-description: cannot read {source}: {e}");
        std::process::exit(1)
    });
    let (description, terminals) = fmi_build::fmi3_files(&xml).unwrap_or_else(|problems| {
        eprintln!("fmi3-description: {source} cannot be converted:");
        problems.iter().for_each(|p| eprintln!("  - {p}"));
        std::process::exit(1)
    });
    let folder = std::path::Path::new(folder);
    std::fs::create_dir_all(folder.join("terminalsAndIcons")).expect("output folder");
    std::fs::write(folder.join("modelDescription.xml"), description).expect("write modelDescription.xml");
    std::fs::write(folder.join("terminalsAndIcons").join("terminalsAndIcons.xml"), terminals).expect("write terminalsAndIcons.xml");
}
