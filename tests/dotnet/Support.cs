// What the NUnit tests of the VCI .NET assembly share: a private canemud in stepped time on a
// configuration of the test's own (as tests/system's VciDaemon and canemu.testing.Daemon start
// it), stepping its time, and adapters opened as a VCI .NET program opens them.
using System;
using System.Collections;
using System.Collections.Generic;
using System.Diagnostics;
using System.IO;
using System.Text;
using System.Threading;
using Ixxat.Vci3;
using Ixxat.Vci3.Bal;
using Ixxat.Vci3.Bal.Can;
using NUnit.Framework;

// No test may hang the suite: each ends within a minute.
[assembly: NUnit.Framework.Timeout(60000)]

namespace Canemu.Tests
{
  // A fixture each of whose tests has a canemud of its own on Config (TwoAdapters unless the
  // fixture says otherwise), started before the test and stopped after it.
  [TestFixture]
  public abstract class DaemonFixture
  {
    protected Daemon daemon;

    protected virtual string Config { get { return Daemon.TwoAdapters; } }

    [SetUp] public void StartDaemon() { daemon = new Daemon(Config); }
    [TearDown] public void StopDaemon() { daemon.Dispose(); }
  }

  // canemud from this build ($CANEMUD), stopped when disposed.
  public sealed class Daemon : IDisposable
  {
    public const string TwoAdapters =
        "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n" +
        "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n" +
        "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";
    // TwoAdapters and gamma, with a CAN controller on can0 and a LIN controller on lin0.
    public const string WithLin = TwoAdapters +
        "\n[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n" +
        "[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\nlin = [\"lin0\"]\n";

    readonly Process process;
    readonly StringBuilder log = new StringBuilder();
    public readonly string Dir, Socket;

    public Daemon(string config, string time = "stepped", params string[] args)
    {
      Dir = Path.Combine(Path.GetTempPath(), "canemu-dotnet-" + Guid.NewGuid().ToString("N").Substring(0, 12));
      Directory.CreateDirectory(Dir);
      Socket = Path.Combine(Dir, "canemud.sock");
      string configPath = Path.Combine(Dir, "canemu.toml");
      File.WriteAllText(configPath, config);
      var canemud = Environment.GetEnvironmentVariable("CANEMUD") ?? "canemud";
      var info = new ProcessStartInfo(canemud, "--time=" + time + " --config=" + configPath + " --socket=" + Socket + " " + string.Join(" ", args))
      {
        UseShellExecute = false, RedirectStandardError = true, RedirectStandardOutput = true,
      };
      process = Process.Start(info);
      var ready = new ManualResetEvent(false);
      process.ErrorDataReceived += (s, e) =>
      {
        if (e.Data == null) { ready.Set(); return; }
        lock (log) log.AppendLine(e.Data);
        if (e.Data.Contains("listening on " + Socket)) ready.Set();
      };
      process.BeginErrorReadLine();
      process.BeginOutputReadLine();
      if (!ready.WaitOne(15000) || process.HasExited)
        Assert.Fail("canemud did not start; its log:\n" + Log);
      Emulator.Connect(Socket);
    }

    public string Log { get { lock (log) return log.ToString(); } }
    public bool Running { get { return !process.HasExited; } }

    public void Dispose()
    {
      try { if (!process.HasExited) { process.Kill(); process.WaitForExit(5000); } } catch (Exception) { }
      try { Directory.Delete(Dir, true); } catch (Exception) { }
    }
  }

  public static class T
  {
    // Runs stepped time ms milliseconds further.
    public static void Step(double ms) { Emulator.StepTime((ulong)(ms * 1e6)); }

    // Steps 1 ms at a time until done() or limit ms passed (for calls that block while simulated
    // time passes, in another thread).
    public static void StepUntil(Func<bool> done, int limitMs = 60000)
    {
      for (int i = 0; i < limitMs && !done(); i++) { Emulator.StepTime(1000000); Thread.Sleep(0); }
    }

    public static List<IVciDevice> Devices()
    {
      var list = new List<IVciDevice>();
      using (var manager = VciServer.GetDeviceManager())
      using (var devices = manager.GetDeviceList())
      {
        IEnumerator e = devices.GetEnumerator();
        while (e.MoveNext()) list.Add((IVciDevice)e.Current);
      }
      return list;
    }

    public static IVciDevice Device(string name)
    {
      foreach (var d in Devices()) if (d.Description.Contains("canemu " + name + ")")) return d;
      Assert.Fail("no adapter " + name);
      return null;
    }

    public static IBalObject Bal(string name) { return Device(name).OpenBusAccessLayer(); }

    public static T2 Open<T2>(IBalObject bal, byte port = 0) where T2 : class
    {
      return (T2)bal.OpenSocket(port, typeof(T2));
    }

    public static CanMessage Msg(uint id, params byte[] data)
    {
      var m = new CanMessage();
      m.FrameType = CanMsgFrameType.Data;
      m.Identifier = id;
      m.DataLength = (byte)data.Length;
      for (int i = 0; i < data.Length; i++) m[i] = data[i];
      return m;
    }

    // All messages of the reader (data only unless told).
    public static List<CanMessage> Drain(ICanMessageReader r, bool dataOnly = true)
    {
      var got = new List<CanMessage>();
      CanMessage m;
      while (r.ReadMessage(out m)) if (!dataOnly || m.FrameType == CanMsgFrameType.Data) got.Add(m);
      return got;
    }

    public static VciException Throws(TestDelegate call)
    {
      try { call(); }
      catch (VciException e) { return e; }
      Assert.Fail("no VciException");
      return null;
    }
  }

  // A line opened as a program opens it: BAL, control unit, one channel with reader and writer,
  // initialized at 500 kbit/s (or as told) and started.
  public sealed class Line : IDisposable
  {
    public readonly IBalObject Bal;
    public readonly ICanControl Control;
    public readonly ICanChannel Channel;
    public readonly ICanMessageReader Reader;
    public readonly ICanMessageWriter Writer;

    public Line(string device, bool start = true,
                CanOperatingModes mode = CanOperatingModes.Standard | CanOperatingModes.Extended | CanOperatingModes.ErrFrame,
                CanBitrate? bitrate = null, bool exclusive = false, bool control = true)
    {
      Bal = T.Bal(device);
      Channel = T.Open<ICanChannel>(Bal);
      Channel.Initialize(256, 64, exclusive);
      Reader = Channel.GetMessageReader();
      Writer = Channel.GetMessageWriter();
      Channel.Activate();
      if (!control) return;
      Control = T.Open<ICanControl>(Bal);
      Control.InitLine(mode, bitrate ?? CanBitrate.Cia500KBit);
      if (start) Control.StartLine();
    }

    public List<CanMessage> Data() { return T.Drain(Reader); }
    public List<CanMessage> All() { return T.Drain(Reader, false); }
    public void Send(CanMessage m) { Assert.IsTrue(Writer.SendMessage(m)); }

    public void Dispose()
    {
      Reader.Dispose();
      Writer.Dispose();
      Channel.Dispose();
      if (Control != null) Control.Dispose();
      Bal.Dispose();
    }
  }
}
