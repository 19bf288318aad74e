// The manual's example programs (client/examples/dotnet/vci_manual_examples.cs), compiled
// unchanged against the assembly, run against canemud in real time: what they print.
using System;
using System.Diagnostics;
using System.IO;
using NUnit.Framework;

namespace Canemu.Tests
{
  [TestFixture]
  public class ExampleTests
  {
    const string Config =
        "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 125000\n\n" +
        "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n" +
        "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\nlin = [\"lin0\"]\n\n" +
        "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n" +
        "[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n" +
        "[[lin_node]]\nname = \"master\"\nbus = \"lin0\"\nschedule = \"s\"\n\n" +
        "[[lin_node.schedules]]\nname = \"s\"\nslots = [ { frame = 0x10, delay = \"10ms\" } ]\n\n" +
        "[[lin_node.response]]\nid = 0x10\ndata = [0x11, 0x22]\n";

    static string Run(string exe, string socket, out int status)
    {
      string bin = Environment.GetEnvironmentVariable("CANEMU_BIN");
      Assert.IsNotNull(bin, "CANEMU_BIN: the build's bin directory");
      var info = new ProcessStartInfo("mono", Path.Combine(bin, exe))
      {
        UseShellExecute = false, RedirectStandardOutput = true, RedirectStandardError = true,
      };
      info.EnvironmentVariables["CANEMU_SOCKET"] = socket;
      using (var p = Process.Start(info))
      {
        string err = null;
        p.ErrorDataReceived += (s, e) => { if (e.Data != null) err += e.Data + "\n"; };
        p.BeginErrorReadLine();
        string output = p.StandardOutput.ReadToEnd();
        if (!p.WaitForExit(60000)) { p.Kill(); Assert.Fail(exe + " did not end"); }
        p.WaitForExit();
        status = p.ExitCode;
        return output + (err ?? "");
      }
    }

    [Test]
    public void TheManualsFragmentsRunAsWritten()
    {
      using (var daemon = new Daemon(Config, "realtime"))
      {
        int status;
        string output = Run("vci_manual_examples.exe", daemon.Socket, out status);
        Assert.AreEqual(0, status, output);
        Assert.AreEqual(
            "AutoInitLine: BTR0=0x03 BTR1=0x1C (125000 bit/s)\n" +
            "Send: True\n" +
            "ReadMessage: 100 [0]\n" +
            "ReadMessage: 200 RTR [3]\n" +
            "ReadMessage: 300 [2] 01 AF\n" +
            "Send: True\n" +
            "ReadMessages: 100 [0]\n" +
            "ReadMessages: 200 RTR [3]\n" +
            "ReadMessages: 300 [2] 01 AF\n" +
            "LIN ReadMessage: 10 [2] 11 22\n" +
            "LIN ReadMessages: 10 [2] 11 22\n", output.Replace("\r", ""));
        Assert.IsTrue(daemon.Running, "canemud is still there");
      }
    }
  }
}
