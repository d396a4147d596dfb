//! fmi2Instantiate: what it refuses (GUID, fmuType), what odd but legal
//! arguments it tolerates; fmi2GetTypesPlatform and fmi2GetVersion.

use super::scene::*;
use crate::*;
use crate::Tested;

/// Proves that fmi2Instantiate refuses a wrong or NULL GUID and every
/// fmuType other than fmi2ModelExchange (0) and fmi2CoSimulation (1), which
/// the description offers, by returning NULL and logging one fmi2Error line
/// that says why (under the given instance name).
pub fn instantiate_refuses_wrong_guid_and_fmu_type<M: Tested>() {
    let guid = M::description().guid.to_string();
    let cases: Vec<(Setup<M>, Vec<String>)> = vec![
        (
            Setup { guid: Some("{00000000-0000-0000-0000-000000000000}".into()), ..Setup::default() },
            vec!["GUID".into(), "{00000000-0000-0000-0000-000000000000}".into(), guid.clone()],
        ),
        (Setup { guid: Some(String::new()), ..Setup::default() }, vec!["GUID".into(), guid.clone()]),
        (Setup { guid: None, ..Setup::default() }, vec!["GUID".into(), guid.clone()]),
        (Setup { fmu_type: 2, ..Setup::default() }, vec!["fmuType = 2".into(), "Co-Simulation (1)".into()]),
        (Setup { fmu_type: 7, ..Setup::default() }, vec!["fmuType = 7".into()]),
        (Setup { fmu_type: -1, ..Setup::default() }, vec!["fmuType = -1".into()]),
    ];
    for (setup, needles) in cases {
        let Err(lines) = instantiate(&Setup { name: Some("refused".into()), ..setup.clone() }) else {
            panic!("GUID {:?}, fmuType {} must be refused", setup.guid, setup.fmu_type);
        };
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        assert_one_error(&lines, &needles);
        assert!(lines[0].message.contains("fmi2Instantiate"), "{lines:?}");
        assert_eq!(lines[0].instance, "refused");
    }
    // The control: the right GUID in upper case is a different string, and refused too.
    assert!(instantiate(&Setup::<M> { guid: Some(guid.to_uppercase()), ..Setup::default() }).is_err());
    assert!(instantiate(&Setup::<M>::default()).is_ok());
    let model_exchange = instantiate(&Setup::<M> { fmu_type: ME, ..Setup::default() });
    assert_eq!(model_exchange.is_ok(), M::description().model_exchange, "fmi2ModelExchange as the description offers it");
}

/// Proves that odd but legal arguments are tolerated: a NULL resource
/// location, empty, non-ASCII and printf-like instance names (passed to the
/// logger unchanged as instanceName), a NULL instance name, a NULL logger,
/// and a NULL callback-functions pointer (refused with NULL, no crash). A
/// model that cannot exist without its resources (`Tested::needs_resources`)
/// is given them for the names, and must refuse the NULL resource location
/// with one line under the instance's name that says what it could not read
/// and why.
pub fn instantiate_tolerates_odd_names_and_null_resources<M: Tested>() {
    let resource_location = if M::needs_resources() { Setup::<M>::default().resource_location } else { None };
    let names = ["", "Bahn-Zugspannung_ÄÖÜ_张力_🧻", "span %s %d %n %%", "a b\tc"];
    for name in names {
        let setup = Setup { name: Some(name.into()), resource_location: resource_location.clone(), logging_on: true, ..Setup::default() };
        let fmu = Fmu::<M>::with(&setup);
        fmu.init(0.0);
        assert_eq!(fmu.do_step(0.0, 0.01), OK, "{:?}", fmu.logs());
        let lines = fmu.take_logs();
        assert!(!lines.is_empty());
        for line in &lines {
            assert_eq!(line.instance, name, "{line:?}");
        }
        // An error message under the same name.
        assert_eq!(fmu.enter_init(), ERROR);
        assert_eq!(fmu.take_logs()[0].instance, name);
    }
    let fmu = Fmu::<M>::with(&Setup { name: None, resource_location: resource_location.clone(), ..Setup::default() });
    fmu.init(0.0);
    assert_eq!(fmu.do_step(0.0, 0.01), OK);
    let fmu = Fmu::<M>::with(&Setup { no_logger: true, ..Setup::default() });
    assert_eq!(fmu.do_step(0.0, 0.01), ERROR, "errors without a logger are returned, not crashed on");
    assert_eq!(fmu.reset(), OK);
    fmu.init(0.0);
    assert!(!instantiate_without_callbacks::<M>(), "NULL functions: nothing to report with, so NULL");
    if M::needs_resources() {
        for name in ["without resources", "span %s %d %n %%"] {
            let Err(lines) = instantiate(&Setup::<M> { name: Some(name.into()), resource_location: None, ..Setup::default() }) else {
                panic!("instantiated without the resources it needs");
            };
            assert_one_error(&lines, &["fmi2Instantiate", "resources/", "no fmuResourceLocation (NULL)"]);
            assert_eq!(lines[0].instance, name);
        }
    }
}

/// Proves fmi2GetTypesPlatform and fmi2GetVersion.
pub fn types_platform_and_version<M: Tested>() {
    assert_eq!(types_platform(), "default");
    assert_eq!(version(), "2.0");
}
