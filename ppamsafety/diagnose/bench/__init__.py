"""Diagnosis of actuator records (one muscle or cylinder on a test bench): the pipeline
against the nominal force law, the tester's candidate library, the tester-record generator
and its blind battery."""
